//! Mesh files: OBJ loading (closed meshes only) and placement in the scene (`scale` and
//! `translate`, or `fit`), each file loaded once per scene.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use sph_core::{TriangleMesh, Vec3};

use crate::error::Ctx;
use crate::geom::v3;
use crate::limits::MAX_MESH_FILE_BYTES;
use crate::raw::{RawBox, RawFluid, RawSolid};
use crate::read::read_limited;
use crate::{MeshPlacement, MeshSpec, SceneError};

/// The mesh fields of a `[[fluid]]` or `[[solid]]` table of `kind = "mesh"`, as written.
#[derive(Debug, Clone, Copy)]
pub(crate) struct MeshFields<'a> {
    /// Mesh file, relative to the scene file's directory.
    pub path: Option<&'a str>,
    /// Uniform scale.
    pub scale: Option<f64>,
    /// Translation (m).
    pub translate: Option<[f64; 3]>,
    /// Box to fit the mesh into, instead of scale/translate.
    pub fit: Option<RawBox>,
}

impl<'a> MeshFields<'a> {
    /// The mesh fields of a `[[fluid]]` table.
    pub fn of_fluid(f: &'a RawFluid) -> Self {
        MeshFields {
            path: f.path.as_deref(),
            scale: f.scale,
            translate: f.translate,
            fit: f.fit,
        }
    }

    /// The mesh fields of a `[[solid]]` table.
    pub fn of_solid(s: &'a RawSolid) -> Self {
        MeshFields {
            path: s.path.as_deref(),
            scale: s.scale,
            translate: s.translate,
            fit: s.fit,
        }
    }
}

/// Loads the meshes of one scene, each file once.
pub(crate) struct MeshLoader<'a> {
    /// Directory that mesh paths are relative to.
    base: &'a Path,
    /// Meshes loaded so far (as in the file), by resolved path.
    cache: HashMap<PathBuf, Arc<TriangleMesh<f64>>>,
}

impl<'a> MeshLoader<'a> {
    /// A loader resolving mesh paths against `base`.
    pub fn new(base: &'a Path) -> Self {
        MeshLoader {
            base,
            cache: HashMap::new(),
        }
    }

    /// Loads (or reuses) and places the mesh of the table at `field`.
    pub fn mesh_spec(
        &mut self,
        ctx: &Ctx,
        field: &str,
        m: MeshFields,
    ) -> Result<MeshSpec, SceneError> {
        let Some(path) = m.path else {
            return Err(ctx.invalid(
                format!("{field}.path"),
                "missing (required for kind = \"mesh\")",
            ));
        };
        let resolved = self.base.join(path);
        let raw = self.load(ctx, field, &resolved)?;
        let (placement, s, t) = match m.fit {
            Some(fit) => {
                if m.scale.is_some() || m.translate.is_some() {
                    return Err(ctx.invalid(
                        format!("{field}.fit"),
                        "give either fit or scale/translate, not both",
                    ));
                }
                fit_placement(ctx, field, &raw, &fit)?
            }
            None => {
                let s = m.scale.unwrap_or(1.0);
                ctx.positive(&format!("{field}.scale"), s)?;
                let t = m.translate.unwrap_or([0.0; 3]);
                ctx.finite3(&format!("{field}.translate"), &t)?;
                let placement = MeshPlacement::Transform {
                    scale: s,
                    translate: t,
                };
                (placement, s, v3(t))
            }
        };
        let placed = raw
            .transformed(s, t)
            .map_err(|e| ctx.invalid(format!("{field}.scale"), format!("placing the mesh: {e}")))?;
        Ok(MeshSpec {
            path: resolved,
            placement,
            mesh: Arc::new(placed),
        })
    }

    /// The mesh file `resolved`, loaded on first use.
    fn load(
        &mut self,
        ctx: &Ctx,
        field: &str,
        resolved: &Path,
    ) -> Result<Arc<TriangleMesh<f64>>, SceneError> {
        if let Some(m) = self.cache.get(resolved) {
            return Ok(m.clone());
        }
        let m = Arc::new(load_obj(resolved).map_err(|reason| SceneError::Mesh {
            file: ctx.file.to_path_buf(),
            field: format!("{field}.path"),
            mesh: resolved.to_path_buf(),
            reason,
        })?);
        self.cache.insert(resolved.to_path_buf(), m.clone());
        Ok(m)
    }
}

/// The placement fitting `mesh` into the box `fit`: the placement, the scale and the
/// translation.
fn fit_placement(
    ctx: &Ctx,
    field: &str,
    mesh: &TriangleMesh<f64>,
    fit: &RawBox,
) -> Result<(MeshPlacement, f64, Vec3<f64>), SceneError> {
    let b = ctx.check_box(&format!("{field}.fit"), &fit.min, &fit.max)?;
    let mb = mesh.bounds();
    let (me, be) = (mb.extent(), b.extent());
    let mut s = f64::INFINITY;
    for a in 0..3 {
        if me[a] > 0.0 {
            s = s.min(be[a] / me[a]);
        }
    }
    if !(s.is_finite() && s > 0.0) {
        return Err(ctx.invalid(
            format!("{field}.fit"),
            "cannot fit the mesh into this box (degenerate mesh or box)",
        ));
    }
    let t = b.center() - mb.center() * s;
    let placement = MeshPlacement::Fit {
        min: fit.min,
        max: fit.max,
    };
    Ok((placement, s, t))
}

/// The field an error about where a placed mesh lies should name: `fit` or `translate`.
pub(crate) fn placement_field(field: &str, m: &MeshSpec) -> String {
    match m.placement {
        MeshPlacement::Fit { .. } => format!("{field}.fit"),
        MeshPlacement::Transform { .. } => format!("{field}.translate"),
    }
}

/// Reads a closed triangle mesh from an OBJ file of at most [`MAX_MESH_FILE_BYTES`] (see
/// [`crate::obj`]; every error names the line).
fn load_obj(path: &Path) -> Result<TriangleMesh<f64>, String> {
    let bytes = read_limited(path, MAX_MESH_FILE_BYTES, "mesh file (MAX_MESH_FILE_BYTES)")?;
    let text = String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let line = e.as_bytes()[..at].iter().filter(|&&b| b == b'\n').count() + 1;
        format!("line {line}: not UTF-8 text (is it an OBJ file?)")
    })?;
    crate::obj::parse_closed_mesh(&text)
}
