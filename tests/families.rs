//! Every registered family is known to the documentation and draws.
//!
//! The registry (`crates/registry/src/lib.rs`) is the one list of
//! families; the docs keep lists of their own for readers. These tests fail
//! when a family is added to the registry and a list is not updated (such
//! lists once went stale unnoticed; docs/how-to/draw.md keeps none and
//! points to `jamkit shapes`), or when a registered 2D or 3D family cannot
//! be drawn from its example.

use jamkit_draw::Outline;
use jamkit_registry::{EXAMPLES, FAMILIES, supports_dim};

fn read(path: &str) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// The paragraph of `text` that starts at the line containing `marker`
/// and runs to the next blank line.
fn paragraph<'a>(text: &'a str, marker: &str, path: &str) -> &'a str {
    let start = text
        .find(marker)
        .unwrap_or_else(|| panic!("{path}: no line with {marker:?}"));
    let line_start = text[..start].rfind('\n').map_or(0, |k| k + 1);
    let rest = &text[line_start..];
    &rest[..rest.find("\n\n").unwrap_or(rest.len())]
}

#[test]
fn every_registered_family_is_in_the_docs_family_lists() {
    let lists = [
        ("docs/formats.md", "a registered family (`jamkit shapes`)"),
        ("README.md", "Shape families (`jamkit shapes`)"),
    ];
    for (path, marker) in lists {
        let text = read(path);
        let list = paragraph(&text, marker, path);
        for info in FAMILIES {
            let name = format!("`{}`", info.name);
            assert!(
                list.contains(&name),
                "{path}: the family list ({marker:?}) does not name {name}"
            );
        }
    }
}

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
