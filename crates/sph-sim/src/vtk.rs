//! Particle frames for ParaView: legacy VTK poly data (binary, big-endian, as the legacy
//! format requires), written with `vtkio`.

use std::path::Path;

use sph_core::{Real, Vec3};

use crate::error::SimError;
use vtkio::model::{
    Attribute, Attributes, ByteOrder, DataSet, FieldArray, PolyDataPiece, Version, VertexNumbers,
    Vtk,
};

/// One particle frame: positions (m), velocities (m/s), densities (kg/m³) and a stable
/// particle id (the index in the scene's initial order, so that ParaView can follow a
/// particle although the solver reorders them by cell).
#[derive(Debug, Clone, Copy)]
pub struct ParticleFrame<'a, R: Real> {
    /// Simulated time of the frame (s), written as the data set's title.
    pub time_s: f64,
    /// Positions (m).
    pub positions: &'a [Vec3<R>],
    /// Velocities (m/s).
    pub velocities: &'a [Vec3<R>],
    /// Densities (kg/m³).
    pub densities: &'a [R],
    /// Particle ids.
    pub ids: &'a [u32],
    /// The solver's per-particle fields (`sph_solver::FluidSolver::particle_fields`):
    /// `(name, values)`, `k` values per particle.
    pub fields: &'a [(String, Vec<R>)],
}

fn flat(v: &[Vec3<impl Real>]) -> Vec<f32> {
    v.iter()
        .flat_map(|p| {
            [
                p.x.as_f64() as f32,
                p.y.as_f64() as f32,
                p.z.as_f64() as f32,
            ]
        })
        .collect()
}

/// Writes `frame` to `path` (`.vtk`): points with one vertex cell each, and the point data
/// `velocity` (vectors), `speed`, `density` and `id` (scalars), then each solver field: one
/// value per particle as scalars, three as vectors, six (a symmetric tensor `xx, yy, zz, xy,
/// yz, zx`) as a full 3×3 tensor, any other count as an array of that many components in the
/// field `solver_fields`. Coordinates and data are stored in single precision (ParaView's
/// default). A field whose length is not a multiple of the particle count is an error.
pub fn write_particle_frame<R: Real>(
    path: &Path,
    frame: &ParticleFrame<'_, R>,
) -> Result<(), SimError> {
    let n = frame.positions.len();
    if !(frame.velocities.len() == n && frame.densities.len() == n && frame.ids.len() == n) {
        return Err(SimError::output(
            path,
            format!(
                "particle frame arrays differ in length ({} positions, {} velocities, {} densities, {} ids)",
                n,
                frame.velocities.len(),
                frame.densities.len(),
                frame.ids.len()
            ),
        ));
    }
    let speed: Vec<f32> = frame
        .velocities
        .iter()
        .map(|v| v.norm().as_f64() as f32)
        .collect();
    let density: Vec<f32> = frame.densities.iter().map(|d| d.as_f64() as f32).collect();
    let point = vec![
        Attribute::vectors("velocity").with_data(flat(frame.velocities)),
        Attribute::scalars("speed", 1).with_data(speed),
        Attribute::scalars("density", 1).with_data(density),
        Attribute::scalars("id", 1)
            .with_data(frame.ids.iter().map(|&i| i as i32).collect::<Vec<i32>>()),
    ];
    let mut point = point;
    point.extend(field_attributes(path, n, frame.fields)?);
    write_points(
        path,
        frame.positions,
        point,
        format!("particles t = {} s", frame.time_s),
    )
}

/// How many values per particle a solver field of `len` values holds for `n` particles: a
/// positive whole number, or `None` for an empty field of no particles (a pour before its
/// first layer); anything else is an error naming the field.
pub(crate) fn values_per_particle(
    name: &str,
    len: usize,
    n: usize,
) -> Result<Option<usize>, String> {
    match len.checked_div(n) {
        Some(k) if k * n == len && k > 0 => Ok(Some(k)),
        _ if len == 0 && n == 0 => Ok(None),
        _ => Err(format!(
            "solver field {name:?} has {len} values, not a positive multiple of the {n} particles"
        )),
    }
}

/// The point attributes of the solver's fields (see [`write_particle_frame`]).
fn field_attributes<R: Real>(
    path: &Path,
    n: usize,
    fields: &[(String, Vec<R>)],
) -> Result<Vec<Attribute>, SimError> {
    let mut out = Vec::new();
    let mut other = Vec::new();
    for (name, values) in fields {
        let Some(k) = values_per_particle(name, values.len(), n)
            .map_err(|reason| SimError::output(path, reason))?
        else {
            continue;
        };
        let data: Vec<f32> = values.iter().map(|v| v.as_f64() as f32).collect();
        match k {
            1 => out.push(Attribute::scalars(name.as_str(), 1).with_data(data)),
            3 => out.push(Attribute::vectors(name.as_str()).with_data(data)),
            6 => {
                let full: Vec<f32> = data
                    .chunks_exact(6)
                    .flat_map(|c| [c[0], c[3], c[5], c[3], c[1], c[4], c[5], c[4], c[2]])
                    .collect();
                out.push(Attribute::tensors(name.as_str()).with_data(full));
            }
            _ => other.push(FieldArray {
                name: name.clone(),
                elem: k as u32,
                data: data.into(),
            }),
        }
    }
    if !other.is_empty() {
        out.push(Attribute::field("solver_fields").with_field_data(other));
    }
    Ok(out)
}

/// Writes passive points (e.g. the high-resolution points of an upscaling) to `path`
/// (`.vtk`) in the format of [`write_particle_frame`]: points with one vertex cell each and
/// the point data `id` (the index in the solver's list).
pub fn write_point_frame<R: Real>(
    path: &Path,
    time_s: f64,
    positions: &[Vec3<R>],
) -> Result<(), SimError> {
    let ids: Vec<i32> = (0..positions.len()).map(|i| i as i32).collect();
    write_points(
        path,
        positions,
        vec![Attribute::scalars("id", 1).with_data(ids)],
        format!("passive points t = {time_s} s"),
    )
}

/// Legacy VTK poly data: `positions` as vertices with the point attributes `point`.
fn write_points<R: Real>(
    path: &Path,
    positions: &[Vec3<R>],
    point: Vec<Attribute>,
    title: String,
) -> Result<(), SimError> {
    let n = positions.len();
    let n32 = u32::try_from(n)
        .map_err(|_| SimError::output(path, "more than 2^32 particles in one VTK frame"))?;
    let mut verts = Vec::with_capacity(2 * n);
    for i in 0..n32 {
        verts.extend_from_slice(&[1, i]);
    }
    let piece = PolyDataPiece {
        points: flat(positions).into(),
        verts: Some(VertexNumbers::Legacy {
            num_cells: n32,
            vertices: verts,
        }),
        lines: None,
        polys: None,
        strips: None,
        data: Attributes {
            point,
            cell: Vec::new(),
        },
    };
    let vtk = Vtk {
        version: Version::new_legacy(4, 2),
        title,
        byte_order: ByteOrder::BigEndian,
        data: DataSet::inline(piece),
        file_path: None,
    };
    vtk.export_be(path)
        .map_err(|e| SimError::output(path, format!("writing VTK frame: {e}")))
}

/// Largest particle frame [`read_positions`] reads (bytes): 4 GiB, 25 times the
/// 10⁶-particle frame this crate writes (about 40 bytes per particle).
pub const MAX_FRAME_BYTES: u64 = 4 << 30;

/// One particle frame read back ([`read_particle_frame`]).
#[derive(Debug, Clone, PartialEq)]
pub struct FrameRead {
    /// The simulated time (s) in the frame's title (`particles t = … s`), if there.
    pub time_s: Option<f64>,
    /// Positions (m).
    pub positions: Vec<Vec3<f32>>,
    /// Velocities (m/s): the `velocity` point data, `None` if the frame has none (passive
    /// points).
    pub velocities: Option<Vec<Vec3<f32>>>,
    /// The solver's `stress` field (Pa, tension positive; `xx, yy, zz, xy, yz, zx` of the
    /// symmetric tensor written as its full 3×3), `None` if the frame has none.
    pub stress: Option<Vec<[f32; 6]>>,
}

/// Reads the particle positions (m) of one frame written by [`write_particle_frame`] or
/// [`write_point_frame`]. A missing file, a file that is not a regular file or is larger
/// than [`MAX_FRAME_BYTES`], or anything that is not such a frame is a
/// [`SimError::Input`] naming the file and what is wrong.
pub fn read_positions(path: &Path) -> Result<Vec<Vec3<f32>>, SimError> {
    Ok(read_particle_frame(path)?.positions)
}

/// Reads one frame written by [`write_particle_frame`] (or [`write_point_frame`]): its
/// time, positions and velocities, with the errors of [`read_positions`]; a `velocity`
/// array of the wrong length or with a non-finite component is an error too.
pub fn read_particle_frame(path: &Path) -> Result<FrameRead, SimError> {
    let bytes = sph_core::input::read_bytes_limited(path, MAX_FRAME_BYTES, "VTK frame")
        .map_err(SimError::from)?;
    let corrupt = |reason: String| SimError::input(path, format!("not a particle frame: {reason}"));
    if !bytes.starts_with(b"# vtk DataFile Version") {
        return Err(corrupt(
            "no legacy VTK header (the first line must start with \"# vtk DataFile Version\")"
                .into(),
        ));
    }
    let vtk = Vtk::parse_legacy_be(bytes.as_slice()).map_err(|e| {
        corrupt(format!(
            "the legacy VTK parser stopped before the end of the data: the file is truncated or was not written by this crate (vtkio: {e})"
        ))
    })?;
    let time_s = vtk
        .title
        .strip_prefix("particles t = ")
        .and_then(|t| t.strip_suffix(" s"))
        .and_then(|t| t.trim().parse::<f64>().ok());
    let DataSet::PolyData { pieces, .. } = vtk.data else {
        return Err(corrupt("not POLYDATA".into()));
    };
    let mut out = Vec::new();
    let mut vel: Option<Vec<Vec3<f32>>> = Some(Vec::new());
    let mut stress: Option<Vec<[f32; 6]>> = Some(Vec::new());
    for piece in pieces {
        let vtkio::model::Piece::Inline(p) = piece else {
            return Err(corrupt("a piece is not inline".into()));
        };
        let pts: Vec<f32> = p
            .points
            .clone()
            .cast_into()
            .ok_or_else(|| corrupt("the points are not numbers".into()))?;
        if !pts.len().is_multiple_of(3) {
            return Err(corrupt(format!(
                "{} coordinates, not a multiple of 3",
                pts.len()
            )));
        }
        out.extend(pts.chunks(3).map(|c| Vec3::new(c[0], c[1], c[2])));
        let v = p.data.point.iter().find_map(|a| match a {
            Attribute::DataArray(d) if d.name == "velocity" => Some(d.data.clone()),
            _ => None,
        });
        match (v, vel.as_mut()) {
            (Some(data), Some(acc)) => {
                let v: Vec<f32> = data
                    .cast_into()
                    .ok_or_else(|| corrupt("the velocities are not numbers".into()))?;
                if v.len() != pts.len() {
                    return Err(corrupt(format!(
                        "{} velocity components for {} coordinates",
                        v.len(),
                        pts.len()
                    )));
                }
                acc.extend(v.chunks(3).map(|c| Vec3::new(c[0], c[1], c[2])));
            }
            _ => vel = None,
        }
        let sg = p.data.point.iter().find_map(|a| match a {
            Attribute::DataArray(d) if d.name == "stress" => Some(d.data.clone()),
            _ => None,
        });
        match (sg, stress.as_mut()) {
            (Some(data), Some(acc)) => {
                let t: Vec<f32> = data
                    .cast_into()
                    .ok_or_else(|| corrupt("the stresses are not numbers".into()))?;
                if t.len() != 3 * pts.len() {
                    return Err(corrupt(format!(
                        "{} stress components for {} particles (9 each)",
                        t.len(),
                        pts.len() / 3
                    )));
                }
                acc.extend(t.chunks(9).map(|c| [c[0], c[4], c[8], c[1], c[5], c[2]]));
            }
            _ => stress = None,
        }
    }
    for (what, arr) in [
        ("particle", Some(&out)),
        ("velocity of particle", vel.as_ref()),
    ] {
        if let Some((i, p)) = arr.and_then(|a| {
            a.iter()
                .enumerate()
                .find(|(_, p)| !p.iter().all(|x| x.is_finite()))
        }) {
            return Err(corrupt(format!(
                "{what} {i}: {:?} is not finite",
                p.as_slice()
            )));
        }
    }
    Ok(FrameRead {
        time_s,
        positions: out,
        velocities: vel,
        stress,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_round_trips_through_vtkio() {
        let dir = std::env::temp_dir().join(format!("vtk-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("f.vtk");
        let pos = [Vec3::new(1.0f64, 2.0, 3.0), Vec3::new(-1.0, 0.5, 0.25)];
        let vel = [Vec3::new(0.0f64, -1.0, 0.0), Vec3::new(3.0, 4.0, 0.0)];
        let rho = [1000.0f64, 1010.0];
        let ids = [7u32, 3];
        write_particle_frame(
            &path,
            &ParticleFrame {
                time_s: 0.5,
                positions: &pos,
                velocities: &vel,
                densities: &rho,
                ids: &ids,
                fields: &[],
            },
        )
        .unwrap();
        let back = Vtk::import(&path).unwrap();
        let DataSet::PolyData { pieces, .. } = back.data else {
            panic!("not poly data")
        };
        let vtkio::model::Piece::Inline(p) = &pieces[0] else {
            panic!("not inline")
        };
        let pts: Vec<f32> = p.points.clone().cast_into().unwrap();
        assert_eq!(pts, vec![1.0, 2.0, 3.0, -1.0, 0.5, 0.25]);
        assert_eq!(p.num_verts(), 2);
        let names: Vec<&str> = p.data.point.iter().map(|a| a.name()).collect();
        assert_eq!(names, ["velocity", "speed", "density", "id"]);
        let read = read_particle_frame(&path).unwrap();
        assert_eq!(read.time_s, Some(0.5));
        assert_eq!(
            read.positions,
            vec![Vec3::new(1.0f32, 2.0, 3.0), Vec3::new(-1.0, 0.5, 0.25)]
        );
        assert_eq!(
            read.velocities,
            Some(vec![Vec3::new(0.0f32, -1.0, 0.0), Vec3::new(3.0, 4.0, 0.0)])
        );
        write_point_frame(&dir.join("p.vtk"), 0.25, &pos).unwrap();
        let passive = read_particle_frame(&dir.join("p.vtk")).unwrap();
        assert_eq!((passive.time_s, passive.velocities), (None, None));
        std::fs::remove_dir_all(&dir).ok();
        let short = write_particle_frame(
            &dir.join("g.vtk"),
            &ParticleFrame {
                time_s: 0.0,
                positions: &pos,
                velocities: &vel[..1],
                densities: &rho,
                ids: &ids,
                fields: &[],
            },
        );
        assert!(short.unwrap_err().to_string().contains("differ in length"));
    }

    /// Solver fields: a scalar, a symmetric tensor (written as the full 3×3), a two-component
    /// array (in the `solver_fields` field); a field of the wrong length is refused.
    #[test]
    fn solver_fields_are_written_by_their_component_count() {
        let dir = std::env::temp_dir().join(format!("vtk-fields-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let pos = [Vec3::new(0.0f64, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0)];
        let zeros = [Vec3::zeros(); 2];
        let fields = vec![
            ("plastic_strain".to_string(), vec![0.5f64, 0.25]),
            (
                "stress".to_string(),
                vec![
                    1.0, 2.0, 3.0, 4.0, 5.0, 6.0, -1.0, -2.0, -3.0, -4.0, -5.0, -6.0,
                ],
            ),
            ("pair".to_string(), vec![1.0, 2.0, 3.0, 4.0]),
        ];
        let frame = |fields: &[(String, Vec<f64>)], path: &Path| {
            write_particle_frame(
                path,
                &ParticleFrame {
                    time_s: 0.0,
                    positions: &pos,
                    velocities: &zeros,
                    densities: &[1.0, 1.0],
                    ids: &[0, 1],
                    fields,
                },
            )
        };
        let path = dir.join("f.vtk");
        frame(&fields, &path).unwrap();
        let back = Vtk::import(&path).unwrap();
        let DataSet::PolyData { pieces, .. } = back.data else {
            panic!("not poly data")
        };
        let vtkio::model::Piece::Inline(p) = &pieces[0] else {
            panic!("not inline")
        };
        let get = |name: &str| -> Vec<f32> {
            p.data
                .point
                .iter()
                .find_map(|a| match a {
                    Attribute::DataArray(d) if d.name == name => d.data.clone().cast_into::<f32>(),
                    _ => None,
                })
                .unwrap()
        };
        assert_eq!(get("plastic_strain"), vec![0.5, 0.25]);
        // xx, yy, zz, xy, yz, zx = 1..6 → rows (1 4 6), (4 2 5), (6 5 3)
        assert_eq!(
            get("stress")[..9],
            [1.0, 4.0, 6.0, 4.0, 2.0, 5.0, 6.0, 5.0, 3.0]
        );
        let pair = p.data.point.iter().find_map(|a| match a {
            Attribute::Field { name, data_array } if name == "solver_fields" => {
                Some(data_array[0].clone())
            }
            _ => None,
        });
        let pair = pair.unwrap();
        assert_eq!((pair.name.as_str(), pair.elem), ("pair", 2));
        // the reader of the frame still reads it, with the stress in the solver's order
        let read = read_particle_frame(&path).unwrap();
        assert_eq!(read.positions.len(), 2);
        let stress = read.stress.unwrap();
        assert_eq!(stress[0], [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        assert_eq!(stress[1], [-1.0, -2.0, -3.0, -4.0, -5.0, -6.0]);
        let bad = vec![("short".to_string(), vec![1.0f64, 2.0, 3.0])];
        let err = frame(&bad, &dir.join("g.vtk")).unwrap_err().to_string();
        assert!(err.contains("\"short\" has 3 values"), "{err}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
