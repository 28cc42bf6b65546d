//! Scene variants built from a shipped scene file's TOML: the file is read as a TOML table,
//! edited (a solver setting, the fluid block, the tank) and parsed again with
//! [`Scene::parse_str`], so that every variant goes through the scene parser's validation
//! (fluid inside the tank, solver fields in range, unknown fields refused) exactly as a file a
//! user writes would.

use std::path::PathBuf;

use anyhow::{anyhow, bail, Context as _, Result};
use sph_scene::Scene;
use toml::{Table, Value};

use crate::{workspace_root, Mode};

/// A scene file's TOML, being edited.
#[derive(Debug, Clone)]
pub struct SceneText {
    table: Table,
    source: PathBuf,
}

/// The `[quick]` keys and the `section.key` each overrides (as [`Scene::quick`] applies them).
const QUICK_KEYS: [(&str, &str); 6] = [
    ("particle_spacing", "simulation.particle_spacing"),
    ("duration", "simulation.duration"),
    ("frame_dt", "simulation.frame_dt"),
    ("substeps", "solver.substeps"),
    ("iterations", "solver.iterations"),
    ("every_frames", "output.every_frames"),
];

impl SceneText {
    /// The shipped scene `scenes/<name>.toml` with its `[quick]` overrides folded into their
    /// sections in quick mode (and the `[quick]` table dropped in either mode, so that edits
    /// are not overridden later).
    pub fn shipped(name: &str, mode: Mode) -> Result<Self> {
        let source = workspace_root().join("scenes").join(format!("{name}.toml"));
        let text = std::fs::read_to_string(&source)
            .with_context(|| format!("reading scene {}", source.display()))?;
        let mut table: Table = text
            .parse()
            .with_context(|| format!("scene {}: not a TOML table", source.display()))?;
        let quick = table.remove("quick");
        if let (Mode::Quick, Some(Value::Table(quick))) = (mode, quick) {
            for (key, target) in QUICK_KEYS {
                if let Some(v) = quick.get(key) {
                    set_path(&mut table, target, v.clone())?;
                }
            }
        }
        Ok(Self { table, source })
    }

    /// Sets `section.key` (e.g. `"solver.friction_angle_deg"`), creating the section if needed.
    pub fn set(&mut self, path: &str, value: impl Into<Value>) -> Result<&mut Self> {
        set_path(&mut self.table, path, value.into())?;
        Ok(self)
    }

    /// Reads `section.key` as a number (integers widened).
    pub fn number(&self, path: &str) -> Result<f64> {
        let (section, key) = split(path)?;
        match self.table.get(section).and_then(|s| s.get(key)) {
            Some(Value::Float(x)) => Ok(*x),
            Some(Value::Integer(i)) => Ok(*i as f64),
            other => bail!(
                "scene {}: {path} is {other:?}, not a number",
                self.source.display()
            ),
        }
    }

    /// Replaces the `[solver]` table by `kind` and `fields` (the solver's other settings take
    /// their defaults).
    pub fn set_solver(&mut self, kind: &str, fields: &[(&str, Value)]) -> &mut Self {
        let mut solver = Table::new();
        solver.insert("kind".into(), Value::String(kind.into()));
        for (k, v) in fields {
            solver.insert((*k).into(), v.clone());
        }
        self.table.insert("solver".into(), Value::Table(solver));
        self
    }

    /// Replaces the fluids by one block `[min, max]` at rest, and the tank by `[tank_min,
    /// tank_max]` (m).
    pub fn set_block_and_tank(
        &mut self,
        min: [f64; 3],
        max: [f64; 3],
        tank_min: [f64; 3],
        tank_max: [f64; 3],
    ) -> &mut Self {
        let arr = |v: [f64; 3]| Value::Array(v.iter().map(|&x| Value::Float(x)).collect());
        let mut block = Table::new();
        block.insert("kind".into(), Value::String("block".into()));
        block.insert("min".into(), arr(min));
        block.insert("max".into(), arr(max));
        self.table
            .insert("fluid".into(), Value::Array(vec![Value::Table(block)]));
        let mut tank = Table::new();
        tank.insert("min".into(), arr(tank_min));
        tank.insert("max".into(), arr(tank_max));
        self.table.insert("tank".into(), Value::Table(tank));
        self
    }

    /// The edited scene, parsed and validated as a file would be (errors name the source
    /// file and the field).
    pub fn scene(&self) -> Result<Scene> {
        let text = toml::to_string(&self.table)
            .map_err(|e| anyhow!("scene {}: {e}", self.source.display()))?;
        Ok(Scene::parse_str(&text, &self.source)?)
    }
}

fn split(path: &str) -> Result<(&str, &str)> {
    path.split_once('.')
        .ok_or_else(|| anyhow!("scene field path {path:?} is not section.key"))
}

fn set_path(table: &mut Table, path: &str, value: Value) -> Result<()> {
    let (section, key) = split(path)?;
    let entry = table
        .entry(section.to_string())
        .or_insert_with(|| Value::Table(Table::new()));
    match entry {
        Value::Table(t) => {
            t.insert(key.to_string(), value);
            Ok(())
        }
        other => bail!("scene: [{section}] is {other:?}, not a table"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quick_overrides_fold_into_their_sections_and_edits_stay() {
        let mut t = SceneText::shipped("dam_break", Mode::Quick).unwrap();
        assert_eq!(t.number("simulation.particle_spacing").unwrap(), 0.025);
        t.set("solver.substeps", 7).unwrap();
        let s = t.scene().unwrap();
        assert_eq!(s.particle_spacing, 0.025);
        assert_eq!(s.solver.substeps(), 7);
        assert!(s.quick_overrides.is_none());
        let full = SceneText::shipped("dam_break", Mode::Full).unwrap();
        assert_eq!(full.number("simulation.particle_spacing").unwrap(), 0.0125);
    }

    #[test]
    fn edited_block_is_validated_like_a_file() {
        let mut t = SceneText::shipped("dam_break", Mode::Quick).unwrap();
        t.set_block_and_tank([0.0; 3], [0.2, 0.4, 0.1], [0.0; 3], [1.0, 0.5, 0.1]);
        let s = t.scene().unwrap();
        assert_eq!(s.fluid_positions::<f64>().unwrap().len(), 8 * 16 * 4);
        // a block sticking out of the tank is refused by the parser
        t.set_block_and_tank([0.0; 3], [0.2, 0.6, 0.1], [0.0; 3], [1.0, 0.5, 0.1]);
        let err = t.scene().unwrap_err().to_string();
        assert!(err.contains("fluid[0]"), "{err}");
        // an unknown solver field is refused
        t.set_solver("pbf", &[("substeps", 1.into()), ("bogus", 1.into())]);
        assert!(t.scene().is_err());
    }
}
