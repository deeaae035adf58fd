//! How the minimiser and the analysis treat a family's packings: its
//! [`Policy`], plain data returned once.

/// How the minimiser and the analysis treat a family's packings
/// ([`Shape::policy`](crate::Shape::policy)). [`Policy::new`] gives the
/// paper's choices for disks in dimension `dim`; a family changes only the
/// fields it must:
///
/// ```
/// # use jamkit_core::Policy;
/// let policy = Policy { expects_isostatic: false, ..Policy::new(2) };
/// assert_eq!(policy.rattler_threshold, 3);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Policy {
    /// The largest FIRE time step (translations of unit mass, rotations of
    /// [`Shape::rot_inertia`](crate::Shape::rot_inertia)); `None`: the
    /// engine's default 0.5. FIRE's semi-implicit Euler step is stable below
    /// `2/ω_max`, `ω_max` the highest vibration frequency of a jammed
    /// packing, and FIRE crawls well before that limit. A family whose
    /// bodies touch at several points per pair, and so vibrate faster than
    /// spheres (`ω_max² ≈ 12` for 3D dimers against 6 for spheres), says so
    /// here. An experiment's `minimizer.dt_max` overrides it.
    pub fire_dt_max: Option<f64>,
    /// Whether FIRE's masses default to each body's own stiffness block in
    /// the jamming search's minimisations that start from a decompressed
    /// jammed state (`masses: Blocks((jammed_only: true))`), instead of the
    /// bodies' own masses everywhere. Yes where that was measured faster with
    /// the same ensembles (docs/reports/minimizers.md); an experiment's
    /// `minimizer.masses` overrides it. Default: no (the paper's).
    pub jammed_block_masses: bool,
    /// Whether FIRE hands every minimisation to L-BFGS from the start with
    /// the block metric (`lbfgs: (after: 0, blocks: true)`) when the
    /// experiment leaves `minimizer.lbfgs` out and runs FIRE (not FIRE 2.0).
    /// Yes where that was measured faster with the same ensembles
    /// (docs/reports/minimizers.md); an experiment's `minimizer.lbfgs`
    /// overrides it. Default: no (FIRE alone, the paper's).
    pub lbfgs_blocks: bool,
    /// Whether the random start must be free of overlaps. Non-convex bodies
    /// (bodies made of spheres, lobed outlines with the exact gap) can
    /// interpenetrate into a *locked* pair at a random start (two dimers
    /// crossed at their centres feel no net force: a local minimum of the
    /// energy with a finite overlap; two lobed bodies lobes in lobes sit on
    /// a jump of the energy), so they are
    /// placed one by one, each redrawn until it overlaps none placed before
    /// ([`Packing::random`](crate::Packing::random)). Default false: convex
    /// bodies relax any start, and keep their random stream.
    pub overlap_free_start: bool,
    /// Fewest contacts a non-rattler keeps (rattlers are removed iteratively
    /// below this). Default `D + 1`, the paper's choice for disks and
    /// near-disks.
    pub rattler_threshold: usize,
    /// Whether jammed packings are expected to be isostatic
    /// (`N_c ≥ f N_nr − D + 1`, `f = D + rot_dof`): true for spheres and rigid
    /// bodies made of spheres, false for near-disks, which jam hypostatic.
    pub expects_isostatic: bool,
    /// Caveats about these parameters that do not stop a run but qualify its
    /// results (e.g. a non-convex outline where the gap model assumes one
    /// contact per pair). Written into each packing's `flag`.
    pub warnings: Vec<String>,
}

impl Policy {
    /// The paper's choices in dimension `dim`: FIRE with its default step
    /// and the bodies' own masses, a random start that may overlap,
    /// rattlers below `dim + 1` contacts, isostatic packings expected, no
    /// warning.
    pub fn new(dim: usize) -> Self {
        Self {
            fire_dt_max: None,
            jammed_block_masses: false,
            lbfgs_blocks: false,
            overlap_free_start: false,
            rattler_threshold: dim + 1,
            expects_isostatic: true,
            warnings: Vec::new(),
        }
    }
}
