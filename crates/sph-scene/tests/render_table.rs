//! The `[render]` table is kept as written, for the renderer to check (`ssfr-render`).

mod common;

use common::{fixture_dir, VALID};
use sph_scene::Scene;

#[test]
fn render_table_is_kept_raw() {
    let file = fixture_dir("render_table").join("render_table.toml");
    let s = Scene::parse_str(VALID, &file).unwrap();
    assert!(s.render.is_none());
    let text = format!("{VALID}\n[render]\nwidth = 640\n[render.camera]\nfov_deg = 30.0\n");
    let s = Scene::parse_str(&text, &file).unwrap();
    let t = s.render.expect("[render] kept");
    assert_eq!(t["width"].as_integer(), Some(640));
    assert_eq!(t["camera"]["fov_deg"].as_float(), Some(30.0));
    // Its contents are not checked here (the renderer does, with the field path), but a
    // `render` that is not a table is refused.
    let bad = format!("{VALID}\nrender = 3\n");
    assert!(Scene::parse_str(&bad, &file).is_err());
}
