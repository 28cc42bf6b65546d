//! `cargo xtask package-check [--tests]`: the published crates as a user gets them.
//!
//! 1. `cargo package --no-verify` writes the tarball of every crate that is published (all
//!    but the `publish = false` ones, read from `cargo metadata`) to `target/package/`.
//! 2. The tarballs are unpacked into `target/package-check/crates/`, beside a user project
//!    `target/package-check/user/`, one program that runs the example of every crate's
//!    packaged README (its front door) in turn. The unpacked crates and the user project form a
//!    scratch workspace outside this one, whose `[patch.crates-io]` points every published
//!    name at its unpacked crate, so the crates resolve one another by version as they would
//!    from crates.io; this workspace's `Cargo.lock` pins the other dependencies.
//! 3. The user project is built in release against the unpacked crates, sharing this
//!    workspace's `target/` (dependencies compiled by `cargo test --release` are reused), and
//!    program is run. A missing file, re-export or dependency version fails here.
//!
//! With `--tests`, the unpacked crates' own tests (unit, integration, doc) run as well
//! (`cargo test --release --workspace` in the scratch workspace): the packaged tests build
//! and pass from the tarballs. That takes many minutes; CI runs without it.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{bail, Context, Result};

/// The user project's package name.
const USER: &str = "package-check-user";

/// One unpacked crate.
struct Unpacked {
    package: String,
    version: String,
    lib: String,
    dir: PathBuf,
}

/// Runs `cargo ARGS` in `dir` with `envs`, failing on a non-zero exit.
fn cargo_in(dir: &Path, args: &[&str], envs: &[(&str, &Path)]) -> Result<()> {
    let mut c = Command::new(super::cargo());
    c.args(args).current_dir(dir);
    for (k, v) in envs {
        c.env(k, v);
    }
    let status = c
        .status()
        .with_context(|| format!("running cargo {args:?} in {}", dir.display()))?;
    if !status.success() {
        bail!(
            "cargo {} failed in {} ({status})",
            args.join(" "),
            dir.display()
        );
    }
    Ok(())
}

/// `NAME-VERSION.crate` → (`NAME`, `VERSION`): the version starts after the last `-` that is
/// followed by a digit.
fn split_crate_file(stem: &str) -> Option<(&str, &str)> {
    let i = stem
        .char_indices()
        .filter(|&(i, c)| c == '-' && stem[i + 1..].starts_with(|d: char| d.is_ascii_digit()))
        .map(|(i, _)| i)
        .next_back()?;
    Some((&stem[..i], &stem[i + 1..]))
}

/// The library name of a normalised (packaged) manifest: `[lib] name`, else the package name
/// with `-` as `_`.
fn lib_name(manifest: &str, package: &str) -> String {
    let mut in_lib = false;
    for line in manifest.lines() {
        let t = line.trim();
        if t.starts_with('[') {
            in_lib = t == "[lib]";
        } else if in_lib {
            if let Some(v) = t.strip_prefix("name = ") {
                return v.trim_matches('"').to_string();
            }
        }
    }
    package.replace('-', "_")
}

/// The first ```rust block of a README as a module whose `run` returns
/// `Result<(), Box<dyn Error>>`: doc-test hidden lines (`# …`) are kept as code, the closing
/// `Ok::<(), E>(())` becomes `Ok(())`.
fn readme_program(readme: &str, package: &str) -> Result<String> {
    let mut lines = readme.lines().skip_while(|l| l.trim() != "```rust");
    if lines.next().is_none() {
        bail!("{package}: README.md has no ```rust example");
    }
    let mut body = String::new();
    for line in lines.take_while(|l| l.trim() != "```") {
        let code = match line.strip_prefix("# ") {
            Some(hidden) => hidden,
            None if line == "#" => "",
            None => line,
        };
        if code.starts_with("Ok::<") {
            continue;
        }
        writeln!(body, "    {code}")?;
    }
    Ok(format!(
        "//! The README example of `{package}`, built against its packaged crate.\n\
         pub fn run() -> Result<(), Box<dyn std::error::Error>> {{\n{body}    Ok(())\n}}\n"
    ))
}

/// Writes the scratch workspace (manifest, lock file, user project) for `crates`.
fn write_scratch(root: &Path, scratch: &Path, crates: &[Unpacked]) -> Result<()> {
    let user = scratch.join("user");
    std::fs::create_dir_all(user.join("src"))?;
    let (mut mods, mut calls) = (String::new(), String::new());
    let mut ws = String::from(
        "# Written by `cargo xtask package-check`: the packaged crates and a user of them.\n\
         [workspace]\nresolver = \"2\"\nmembers = [\"user\"",
    );
    let mut patch = String::from("\n[patch.crates-io]\n");
    let mut deps = String::new();
    for c in crates {
        write!(ws, ", \"crates/{}-{}\"", c.package, c.version)?;
        writeln!(
            patch,
            "{} = {{ path = \"crates/{}-{}\" }}",
            c.package, c.package, c.version
        )?;
        writeln!(
            deps,
            "{} = {{ package = \"{}\", version = \"={}\" }}",
            c.lib, c.package, c.version
        )?;
        let readme = std::fs::read_to_string(c.dir.join("README.md"))
            .with_context(|| format!("{}: the package has no README.md", c.package))?;
        let program = readme_program(&readme, &c.package)?;
        std::fs::write(user.join(format!("src/front_door_{}.rs", c.lib)), program)?;
        writeln!(mods, "mod front_door_{};", c.lib)?;
        writeln!(
            calls,
            "    (\"{} {}\", front_door_{}::run),",
            c.package, c.version, c.lib
        )?;
    }
    let main = format!(
        "//! Runs the README example of every packaged crate.\n{mods}\n\
         type Example = fn() -> Result<(), Box<dyn std::error::Error>>;\n\n\
         const EXAMPLES: [(&str, Example); {n}] = [\n{calls}];\n\n\
         fn main() {{\n    for (name, run) in EXAMPLES {{\n        if let Err(e) = run() {{\n            \
         eprintln!(\"package-check: the README example of {{name}} failed: {{e}}\");\n            \
         std::process::exit(1);\n        }}\n        \
         println!(\"package-check: {{name}}: README example ran\");\n    }}\n}}\n",
        n = crates.len()
    );
    std::fs::write(user.join("src/main.rs"), main)?;
    ws.push_str("]\n");
    ws.push_str(&patch);
    ws.push_str("\n[profile.release]\ndebug = 1\n");
    std::fs::write(scratch.join("Cargo.toml"), ws)?;
    std::fs::write(
        user.join("Cargo.toml"),
        format!(
            "[package]\nname = \"{USER}\"\nversion = \"0.0.0\"\nedition = \"2021\"\n\
             publish = false\n\n[dependencies]\n{deps}"
        ),
    )?;
    // The workspace's versions of every other dependency (and so its compiled artifacts).
    std::fs::copy(root.join("Cargo.lock"), scratch.join("Cargo.lock"))?;
    Ok(())
}

/// The workspace's packages that are published (`publish` not `false`).
fn published_packages(root: &Path) -> Result<Vec<String>> {
    let out = Command::new(super::cargo())
        .args(["metadata", "--no-deps", "--format-version", "1"])
        .current_dir(root)
        .output()
        .context("running cargo metadata")?;
    if !out.status.success() {
        bail!(
            "cargo metadata failed: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let meta: serde_json::Value = serde_json::from_slice(&out.stdout)?;
    let mut names = Vec::new();
    for p in meta["packages"]
        .as_array()
        .context("cargo metadata: no packages")?
    {
        // `publish = false` is an empty registry list; absent (`null`) means crates.io.
        let unpublished = p["publish"].as_array().is_some_and(|r| r.is_empty());
        if !unpublished {
            names.push(
                p["name"]
                    .as_str()
                    .context("a package without a name")?
                    .to_string(),
            );
        }
    }
    Ok(names)
}

/// Unpacks every `*.crate` of `packages` into `into`.
fn unpack(packages: &Path, into: &Path) -> Result<Vec<Unpacked>> {
    let mut crates = Vec::new();
    for entry in std::fs::read_dir(packages)? {
        let path = entry?.path();
        if path.extension().is_none_or(|e| e != "crate") {
            continue;
        }
        let stem = path.file_stem().unwrap_or_default().to_string_lossy();
        let Some((package, version)) = split_crate_file(&stem) else {
            bail!("{}: not NAME-VERSION.crate", path.display());
        };
        // `m`: files get the time of unpacking, not the archive's, so that cargo never takes
        // an earlier check's artifacts for these sources as fresh.
        let status = Command::new("tar")
            .arg("xzmf")
            .arg(&path)
            .arg("-C")
            .arg(into)
            .status()
            .context("running tar")?;
        if !status.success() {
            bail!("tar could not unpack {}", path.display());
        }
        let dir = into.join(stem.as_ref());
        let manifest = std::fs::read_to_string(dir.join("Cargo.toml"))?;
        crates.push(Unpacked {
            lib: lib_name(&manifest, package),
            package: package.to_string(),
            version: version.to_string(),
            dir,
        });
    }
    crates.sort_by(|a, b| a.package.cmp(&b.package));
    Ok(crates)
}

/// The task; `tests` also runs the packaged crates' own tests.
pub fn run(tests: bool) -> Result<()> {
    let root = super::workspace_root();
    let target = root.join("target");
    let packages = target.join("package");
    if packages.is_dir() {
        for entry in std::fs::read_dir(&packages)? {
            let path = entry?.path();
            if path.extension().is_some_and(|e| e == "crate") {
                std::fs::remove_file(&path)?;
            }
        }
    }
    let published = published_packages(&root)?;
    // `--allow-dirty`: a developer checks the work tree as it is; CI's clone is clean.
    let mut args = vec!["package", "--no-verify", "--allow-dirty", "--quiet"];
    for p in &published {
        args.extend(["-p", p.as_str()]);
    }
    cargo_in(&root, &args, &[])?;
    let scratch = target.join("package-check");
    if scratch.exists() {
        std::fs::remove_dir_all(&scratch)?;
    }
    let unpacked = scratch.join("crates");
    std::fs::create_dir_all(&unpacked)?;
    let crates = unpack(&packages, &unpacked)?;
    if crates.is_empty() {
        bail!("no crate was packaged in {}", packages.display());
    }
    write_scratch(&root, &scratch, &crates)?;
    let env = [("CARGO_TARGET_DIR", target.as_path())];
    cargo_in(
        &scratch,
        &["build", "--release", "--quiet", "-p", USER],
        &env,
    )?;
    let bin = target.join(format!("release/{USER}"));
    let status = Command::new(&bin)
        .status()
        .with_context(|| format!("running {}", bin.display()))?;
    if !status.success() {
        bail!("a README example failed ({status})");
    }
    if tests {
        cargo_in(
            &scratch,
            &["test", "--release", "--workspace", "--exclude", USER],
            &env,
        )?;
    }
    println!(
        "package-check: {} crates packaged and used from their tarballs",
        crates.len()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crate_file_names_split_at_the_version() {
        assert_eq!(
            split_crate_file("sph-core-0.1.0"),
            Some(("sph-core", "0.1.0"))
        );
        assert_eq!(
            split_crate_file("position-based-fluids-0.10.2-rc1"),
            Some(("position-based-fluids", "0.10.2-rc1"))
        );
        assert_eq!(split_crate_file("nodigits"), None);
    }

    #[test]
    fn lib_name_from_manifest() {
        let m = "[package]\nname = \"position-based-fluids\"\n\n[lib]\nname = \"pbf\"\npath = \"src/lib.rs\"\n";
        assert_eq!(lib_name(m, "position-based-fluids"), "pbf");
        assert_eq!(
            lib_name("[package]\nname = \"sph-core\"\n", "sph-core"),
            "sph_core"
        );
    }

    #[test]
    fn readme_example_becomes_main() {
        let readme = "# x\n\n```rust\nuse x::Y;\nlet a = Y::new()?;\n# let b = 1;\n# Ok::<(), x::E>(())\n```\n";
        let p = readme_program(readme, "x").unwrap();
        assert!(
            p.contains("    use x::Y;\n    let a = Y::new()?;\n    let b = 1;\n    Ok(())\n}"),
            "{p}"
        );
        assert!(readme_program("no code", "x").is_err());
    }
}
