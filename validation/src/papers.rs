//! The five papers the workspace implements, as `docs/papers.md` rows them (Bui et al. 2008's
//! model is the crate `elastoplastic-granular`); and the paper → crates → experiments → scenes → reference-data table
//! generated from the registry.
//!
//! Each experiment lives in the folder of the paper whose crates it validates
//! (`src/experiments/<folder>/<id>.rs`, or `<id>/mod.rs` for a large one), and its reference
//! data in `reference-data/<id>/`. The tests below check that layout against the registry and
//! that the table in `docs/papers.md` is the one [`experiment_table`] generates.

use std::fmt::Write as _;
use std::path::Path;

use crate::Experiment;

/// One of the papers of `docs/papers.md` whose crates have experiments (full citations
/// there).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Paper {
    /// Macklin & Müller 2013, "Position Based Fluids".
    MacklinMuller2013,
    /// Neder 2024, real-time simulation of granular matter using SPH (M.Sc. thesis).
    Neder2024,
    /// Im & Chan 2016, SPH neighbour searching and screen-space fluid rendering.
    ImChan2016,
    /// Chegodaeva 2004, symplectic integration of small Solar System bodies.
    Chegodaeva2004,
    /// Bui, Fukagawa, Sako & Ohno 2008, elastic–plastic SPH for geomaterials.
    Bui2008,
}

impl Paper {
    /// The papers, in `docs/papers.md`'s order.
    pub const ALL: [Paper; 5] = [
        Paper::MacklinMuller2013,
        Paper::Neder2024,
        Paper::ImChan2016,
        Paper::Chegodaeva2004,
        Paper::Bui2008,
    ];

    /// The folder of its experiments under `src/experiments/`.
    pub fn folder(self) -> &'static str {
        match self {
            Paper::MacklinMuller2013 => "macklin_muller_2013",
            Paper::Neder2024 => "neder_2024",
            Paper::ImChan2016 => "im_chan_2016",
            Paper::Chegodaeva2004 => "chegodaeva_2004",
            Paper::Bui2008 => "bui_2008",
        }
    }

    /// Authors and year, as the table shows them.
    pub fn short_name(self) -> &'static str {
        match self {
            Paper::MacklinMuller2013 => "Macklin & Müller 2013",
            Paper::Neder2024 => "Neder 2024",
            Paper::ImChan2016 => "Im & Chan 2016",
            Paper::Chegodaeva2004 => "Chegodaeva 2004",
            Paper::Bui2008 => "Bui et al. 2008",
        }
    }

    /// The paper of an experiment: the folder its type's module lives in.
    pub fn of_experiment(e: &dyn Experiment) -> Option<Paper> {
        let mut segments = e.type_path().split("::");
        let folder = segments
            .find(|s| *s == "experiments")
            .and(segments.next())?;
        Paper::ALL.into_iter().find(|p| p.folder() == folder)
    }
}

/// The module name an experiment's file must have: its id with `-` → `_`.
pub fn module_name(id: &str) -> String {
    id.replace('-', "_")
}

/// The Markdown table of every registered experiment, by paper: crates, scenes and the
/// reference-data directory (when `reference_dir/<id>/` exists).
pub fn experiment_table(experiments: &[Box<dyn Experiment>], reference_dir: &Path) -> String {
    let mut s = String::from(
        "| paper | experiment | crates | scenes | reference data |\n| --- | --- | --- | --- | --- |\n",
    );
    let code = |items: &[&str], fmt: &dyn Fn(&str) -> String| -> String {
        if items.is_empty() {
            "—".to_string()
        } else {
            items.iter().map(|i| fmt(i)).collect::<Vec<_>>().join(", ")
        }
    };
    for paper in Paper::ALL {
        for e in experiments
            .iter()
            .filter(|e| Paper::of_experiment(e.as_ref()) == Some(paper))
        {
            let id = e.id();
            let data = if reference_dir.join(id).is_dir() {
                format!("`reference-data/{id}/`")
            } else {
                "—".to_string()
            };
            let _ = writeln!(
                s,
                "| {} | `{id}` | {} | {} | {data} |",
                paper.short_name(),
                code(e.crates(), &|c| format!("`{c}`")),
                code(e.scenes(), &|n| format!("`{n}`")),
            );
        }
    }
    s
}

/// The markers around the generated table in `docs/papers.md`.
pub const TABLE_BEGIN: &str =
    "<!-- experiments: generated from validation's registry; checked by cargo test -p validation -->";
/// See [`TABLE_BEGIN`].
pub const TABLE_END: &str = "<!-- end of experiments -->";

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{registry, workspace_root};

    /// The experiment's file module (the segment before its type name).
    fn file_module(e: &dyn Experiment) -> Option<&'static str> {
        let path = e.type_path();
        let mut segments: Vec<&'static str> = path.split("::").collect();
        segments.pop();
        segments.pop()
    }

    #[test]
    fn every_experiment_lives_in_its_paper_folder_under_its_id() {
        for e in registry() {
            let id = e.id();
            assert!(
                Paper::of_experiment(e.as_ref()).is_some(),
                "{id}: {} is not in a paper folder",
                e.type_path()
            );
            assert_eq!(
                file_module(e.as_ref()),
                Some(module_name(id).as_str()),
                "{id}: its file (or folder) must be named after its id ({})",
                e.type_path()
            );
        }
    }

    #[test]
    fn crates_and_scenes_exist() {
        let root = workspace_root();
        for e in registry() {
            assert!(!e.crates().is_empty(), "{}: names no crate", e.id());
            for c in e.crates() {
                assert!(
                    root.join("crates").join(c).join("Cargo.toml").is_file(),
                    "{}: no crate crates/{c}",
                    e.id()
                );
            }
            for n in e.scenes() {
                assert!(
                    root.join("scenes").join(format!("{n}.toml")).is_file(),
                    "{}: no scene scenes/{n}.toml",
                    e.id()
                );
            }
        }
    }

    #[test]
    fn every_reference_data_directory_is_an_experiment_id() {
        let ids: Vec<&str> = registry().iter().map(|e| e.id()).collect();
        let dir = workspace_root().join("reference-data");
        for entry in std::fs::read_dir(&dir).unwrap() {
            let entry = entry.unwrap();
            if entry.file_type().unwrap().is_dir() {
                let name = entry.file_name().to_string_lossy().into_owned();
                assert!(
                    ids.contains(&name.as_str()),
                    "reference-data/{name}/ is not named after an experiment id"
                );
                assert!(
                    entry.path().join("SOURCE.md").is_file(),
                    "reference-data/{name}/ has no SOURCE.md"
                );
            }
        }
    }

    #[test]
    fn papers_md_holds_the_generated_table() {
        let root = workspace_root();
        let text = std::fs::read_to_string(root.join("docs/papers.md")).unwrap();
        let begin = text
            .find(TABLE_BEGIN)
            .expect("docs/papers.md: no table marker");
        let body = &text[begin + TABLE_BEGIN.len()..];
        let end = body.find(TABLE_END).expect("docs/papers.md: no end marker");
        let table = experiment_table(&registry(), &root.join("reference-data"));
        assert_eq!(
            body[..end].trim(),
            table.trim(),
            "docs/papers.md's experiment table is stale; the generated one is:\n{table}"
        );
    }
}
