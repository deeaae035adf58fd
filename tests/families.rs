//! Every registered family draws from its example, in 2D and in 3D. (That
//! the manual names every family is checked by `tests/reference.rs`, on
//! the generated page docs/reference/families.md.)

use jamkit_draw::Outline;
use jamkit_registry::{EXAMPLES, FAMILIES, supports_dim};

#[test]
fn every_registered_planar_family_draws_from_its_example() {
    assert_eq!(FAMILIES.len(), EXAMPLES.len());
    for (info, example) in FAMILIES.iter().zip(EXAMPLES) {
        if !supports_dim(info, 2) {
            continue;
        }
        let outline = Outline::from_ron(info.name, example)
            .unwrap_or_else(|e| panic!("family `{}` does not draw: {e}", info.name));
        let body = outline.body_points([0.0, 0.0], 1.0, 0.3, 64);
        assert!(
            body.iter().all(|p| p[0].is_finite() && p[1].is_finite()),
            "{}",
            info.name
        );
    }
}

/// Every registered 3D family draws from its example: as balls, through
/// its `Surface`, or from its spheres (`jamkit_draw::scene3d::Solid`), and
/// a body of its example ray-casts to a non-empty picture.
#[test]
fn every_registered_3d_family_draws_from_its_example() {
    use jamkit_draw::render3d::{ShapeBody, body_primitives, body_raster, view_rotation};
    for (info, example) in FAMILIES.iter().zip(EXAMPLES) {
        if !supports_dim(info, 3) {
            continue;
        }
        let params = jamkit_registry::params_from_ron(example).unwrap();
        let primitives = body_primitives(info.name, &params, view_rotation())
            .unwrap_or_else(|e| panic!("family `{}` does not draw in 3D: {e}", info.name));
        let body = ShapeBody {
            label: String::new(),
            primitives,
        };
        let raster = body_raster(&body, 3.0, 20.0);
        assert!(
            raster.count_body(0) > 100,
            "family `{}`: empty picture",
            info.name
        );
    }
}
