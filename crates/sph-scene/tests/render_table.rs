//! The `[render]` table is read as the renderer's typed settings and checked against the
//! scene when the scene is loaded (not only when it is rendered).

mod common;

use common::{fixture_dir, VALID};
use sph_scene::Scene;

#[test]
fn render_table_is_typed_and_resolved_at_load() {
    let file = fixture_dir("render_table").join("render_table.toml");
    let s = Scene::parse_str(VALID, &file).unwrap();
    assert!(s.render.is_none());
    // Defaults frame the tank.
    assert_eq!(s.render_info().tank, Some(([0.0; 3], [2.0, 1.0, 1.0])));
    assert_eq!(s.render_params().unwrap().camera.width, 1280);
    let text = format!("{VALID}\n[render]\nwidth = 640\n[render.camera]\nfov_deg = 30.0\n");
    let s = Scene::parse_str(&text, &file).unwrap();
    let r = s.render.as_ref().expect("[render] read");
    assert_eq!(r.width, Some(640));
    assert_eq!(r.camera.as_ref().and_then(|c| c.fov_deg), Some(30.0));
    let p = s.render_params().unwrap();
    assert_eq!((p.camera.width, p.camera.fov_y_deg), (640, 30.0));
    // A `render` that is not a table is refused, at its field.
    let bad = VALID.replacen("[simulation]", "render = 3\n\n[simulation]", 1);
    let e = Scene::parse_str(&bad, &file).unwrap_err();
    assert_eq!(e.field(), "render", "{e}");
}

#[test]
fn render_nonsense_is_refused_at_load() {
    let file = fixture_dir("render_nonsense").join("scene.toml");
    for (table, field) in [
        ("width = 0\nheight = 0\n", "render.width"),
        ("width = 100000\nheight = 100000\n", "render.width"),
        ("bogus = 1\n", "render.bogus"),
        (
            "[render.camera]\neye = [1.0, 1.0, 1.0]\ntarget = [1.0, 1.0, 1.0]\n",
            "render.camera",
        ),
    ] {
        let text = format!("{VALID}\n[render]\n{table}");
        let e = Scene::parse_str(&text, &file).unwrap_err();
        assert!(e.field().starts_with(field), "{table}: {e}");
    }
}
