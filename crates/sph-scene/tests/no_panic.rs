//! The parser never panics: random strings and random mutations of a valid scene (byte
//! flips, deleted lines, swapped values, replaced numbers) give `Ok` or `Err`.

mod common;

use common::{fixture_dir, VALID};
use proptest::prelude::*;
use sph_scene::Scene;

fn check(text: &str) {
    let dir = fixture_dir("no_panic");
    let file = dir.join("fuzz.toml");
    if let Ok(s) = Scene::parse_str(text, &file) {
        // A scene that parses also samples and builds without error.
        s.fluid_positions::<f32>().unwrap();
        s.quick().fluid_positions::<f64>().unwrap();
        // Validation builds the solids in f64, so that cannot fail; in f32 a value may not
        // fit (e.g. a box too thin), which must be a named error on the tank or a solid.
        s.build_solids::<f64>().unwrap();
        if let Err(e) = s.build_solids::<f32>() {
            let msg = e.to_string();
            assert!(msg.contains("fuzz.toml"), "no file in: {msg}");
            assert!(
                e.field().starts_with("tank") || e.field().starts_with("solid["),
                "unexpected field in: {msg}"
            );
        }
    }
}

fn values(text: &str) -> Vec<(usize, usize)> {
    // Spans of the right-hand sides of `key = value` lines.
    let mut out = Vec::new();
    let mut off = 0;
    for line in text.split_inclusive('\n') {
        if let Some(eq) = line.find(" = ") {
            let start = off + eq + 3;
            let end = off + line.trim_end().len();
            if end > start {
                out.push((start, end));
            }
        }
        off += line.len();
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn random_strings(s in "\\PC{0,200}") {
        check(&s);
    }

    #[test]
    fn random_toml_like(s in "(\\[?[a-z_]{1,12}\\]? ?= ?(-?[0-9.e]{1,8}|\"[a-z./]{0,10}\"|\\[[0-9., -]{0,12}\\]|nan|inf|true)\n){0,12}") {
        check(&s);
    }

    #[test]
    fn byte_flips(flips in prop::collection::vec((0usize..10_000, any::<u8>()), 1..6)) {
        let mut bytes = VALID.as_bytes().to_vec();
        for (pos, b) in flips {
            let n = bytes.len();
            bytes[pos % n] = b;
        }
        check(&String::from_utf8_lossy(&bytes));
    }

    #[test]
    fn deleted_lines(mask in prop::collection::vec(any::<bool>(), 80)) {
        let text: String = VALID
            .split_inclusive('\n')
            .enumerate()
            .filter(|(i, _)| !mask[i % mask.len()] || i % 3 == 0)
            .map(|(_, l)| l)
            .collect();
        check(&text);
    }

    #[test]
    fn swapped_values(a in 0usize..1000, b in 0usize..1000) {
        let spans = values(VALID);
        let (sa, sb) = (spans[a % spans.len()], spans[b % spans.len()]);
        let (first, second) = if sa.0 <= sb.0 { (sa, sb) } else { (sb, sa) };
        if first != second {
            let text = format!(
                "{}{}{}{}{}",
                &VALID[..first.0],
                &VALID[second.0..second.1],
                &VALID[first.1..second.0],
                &VALID[first.0..first.1],
                &VALID[second.1..]
            );
            check(&text);
        }
    }

    #[test]
    fn replaced_values(a in 0usize..1000, v in prop_oneof![
        Just("0".to_string()), Just("-1".to_string()), Just("1e308".to_string()),
        Just("-1e-300".to_string()), Just("nan".to_string()), Just("inf".to_string()),
        Just("[]".to_string()), Just("[1e30, 0, 0]".to_string()), Just("\"x\"".to_string()),
        Just("18446744073709551615".to_string()), Just("{}".to_string()),
        (-5.0..5.0f64).prop_map(|x| format!("{x}")),
    ]) {
        let spans = values(VALID);
        let (s, e) = spans[a % spans.len()];
        let text = format!("{}{}{}", &VALID[..s], v, &VALID[e..]);
        check(&text);
    }
}
