//! A Wavefront OBJ reader for closed triangle meshes that names the line of every problem.
//!
//! Reads the geometry statements only: `v x y z [w | r g b]` (vertex positions) and
//! `f a b c ...` (faces, each corner `v`, `v/vt`, `v//vn` or `v/vt/vn`, 1-based or negative =
//! relative to the last vertex; polygons are split into a fan of triangles around their first
//! corner, as `tobj` and most OBJ readers do). `o`/`g` start a new object; other statements
//! (`vt`, `vn`, `s`, `l`, `p`, `usemtl`, `mtllib`, comments) are ignored. A line ending in `\`
//! continues on the next one.
//!
//! When the faces come from more than one object, vertices at exactly the same position are
//! welded (exporters often give each object its own copy of the shared vertices), so that
//! objects which together enclose a volume form one closed mesh.
//!
//! Every error is a [`String`] naming the 1-based line and what is wrong there; errors found
//! on the whole mesh ([`TriangleMesh::new`], [`TriangleMesh::check_closed`]) name the line
//! of the face the offending triangle comes from.

use std::collections::HashMap;

use sph_core::{MeshError, TriangleMesh, Vec3};

/// The triangles read from an OBJ text, with the line each comes from.
struct ObjMesh {
    vertices: Vec<Vec3<f64>>,
    triangles: Vec<[u32; 3]>,
    /// 1-based line of the face each triangle comes from.
    triangle_lines: Vec<usize>,
    /// Whether the vertices of several objects were welded (vertex numbers then differ
    /// from the file's).
    welded: bool,
}

/// The OBJ statements other than `v`, `f`, `o`, `g`, ignored (Wavefront OBJ specification,
/// appendix B1 of the Advanced Visualizer manual: texture and normal vertices, points and
/// lines, grouping, display and render attributes, free-form geometry).
const OTHER_STATEMENTS: &[&str] = &[
    "vt",
    "vn",
    "vp",
    "p",
    "l",
    "s",
    "mg",
    "usemtl",
    "mtllib",
    "cstype",
    "deg",
    "bmat",
    "step",
    "curv",
    "curv2",
    "surf",
    "parm",
    "trim",
    "hole",
    "scrv",
    "sp",
    "end",
    "con",
    "bevel",
    "c_interp",
    "d_interp",
    "lod",
    "shadow_obj",
    "trace_obj",
    "ctech",
    "stech",
    "maplib",
    "usemap",
    "call",
    "csh",
];

/// Most vertices accepted (triangle corners are `u32`).
const MAX_VERTICES: usize = (u32::MAX / 2) as usize;

/// Reads a closed triangle mesh from OBJ text (see the module documentation).
pub(crate) fn parse_closed_mesh(text: &str) -> Result<TriangleMesh<f64>, String> {
    let obj = parse(text)?;
    let (lines, welded) = (obj.triangle_lines, obj.welded);
    let mesh = TriangleMesh::new(obj.vertices, obj.triangles)
        .map_err(|e| with_face_lines(&e, &lines, welded))?;
    mesh.check_closed()
        .map_err(|e| with_face_lines(&e, &lines, welded))?;
    Ok(mesh)
}

/// The message of a mesh error with the OBJ line of each triangle it names, and how its
/// vertex numbers relate to the file's.
fn with_face_lines(e: &MeshError, lines: &[usize], welded: bool) -> String {
    let line = |t: usize| lines.get(t).copied().unwrap_or(0);
    let numbering = if welded {
        "vertices numbered from 0 after welding the objects' shared positions"
    } else {
        "vertices numbered from 0: the file's numbers are one more"
    };
    match e {
        MeshError::DegenerateTriangle { triangle, .. }
        | MeshError::OpenEdge { triangle, .. }
        | MeshError::IndexOutOfRange { triangle, .. } => {
            format!("line {}: {e} ({numbering})", line(*triangle))
        }
        MeshError::InconsistentOrientation { first, second, .. } => {
            format!(
                "lines {} and {}: {e} ({numbering})",
                line(*first),
                line(*second)
            )
        }
        _ => e.to_string(),
    }
}

/// The logical lines of `text` (continuations joined) with their first physical line.
fn logical_lines(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut pending: Option<(usize, String)> = None;
    for (i, raw) in text.lines().enumerate() {
        let (start, mut acc) = pending.take().unwrap_or((i + 1, String::new()));
        let line = raw.trim_end();
        if let Some(head) = line.strip_suffix('\\') {
            acc.push_str(head);
            acc.push(' ');
            pending = Some((start, acc));
        } else {
            acc.push_str(line);
            out.push((start, acc));
        }
    }
    out.extend(pending);
    out
}

fn parse(text: &str) -> Result<ObjMesh, String> {
    let mut vertices: Vec<Vec3<f64>> = Vec::new();
    let mut triangles = Vec::new();
    let mut triangle_lines = Vec::new();
    // Objects (`o`/`g`) that have faces: welding applies when there is more than one.
    let mut objects_with_faces = 0usize;
    let mut current_has_faces = false;
    let mut corners: Vec<u32> = Vec::new();
    for (line_no, line) in logical_lines(text) {
        let body = line.split('#').next().unwrap_or("");
        let mut tokens = body.split_whitespace();
        let Some(keyword) = tokens.next() else {
            continue;
        };
        let at = |what: String| format!("line {line_no}: {what}");
        match keyword {
            "v" => {
                let values: Vec<&str> = tokens.collect();
                if !matches!(values.len(), 3 | 4 | 6 | 7) {
                    return Err(at(format!(
                        "vertex needs 3 coordinates (x y z, optionally w or r g b), found {} value(s)",
                        values.len()
                    )));
                }
                let mut p = [0.0; 3];
                for (a, tok) in values.iter().take(3).enumerate() {
                    let v: f64 = tok.parse().map_err(|_| {
                        at(format!(
                            "vertex coordinate {} is not a number: {tok:?}",
                            ['x', 'y', 'z'][a]
                        ))
                    })?;
                    if !v.is_finite() {
                        return Err(at(format!(
                            "vertex coordinate {} is not finite ({tok})",
                            ['x', 'y', 'z'][a]
                        )));
                    }
                    p[a] = v;
                }
                if vertices.len() >= MAX_VERTICES {
                    return Err(at(format!("more than {MAX_VERTICES} vertices")));
                }
                vertices.push(Vec3::new(p[0], p[1], p[2]));
            }
            "f" => {
                corners.clear();
                for tok in tokens {
                    corners.push(face_corner(tok, vertices.len()).map_err(at)?);
                }
                if corners.len() < 3 {
                    return Err(at(format!(
                        "face needs at least 3 vertices, found {}",
                        corners.len()
                    )));
                }
                for (k, &c) in corners.iter().enumerate() {
                    if corners[..k].contains(&c) {
                        return Err(at(format!(
                            "face uses vertex {} twice (a degenerate face)",
                            c + 1
                        )));
                    }
                }
                for k in 1..corners.len() - 1 {
                    triangles.push([corners[0], corners[k], corners[k + 1]]);
                    triangle_lines.push(line_no);
                }
                if !current_has_faces {
                    current_has_faces = true;
                    objects_with_faces += 1;
                }
            }
            "o" | "g" => current_has_faces = false,
            k if OTHER_STATEMENTS.contains(&k) => {}
            k => {
                let shown: String = k.chars().take(16).collect();
                return Err(at(format!(
                    "unknown OBJ statement {shown:?} (is this a text OBJ file?)"
                )));
            }
        }
    }
    if triangles.is_empty() {
        return Err(format!(
            "no faces: {} vertices read but no `f` line (a closed mesh needs triangles; is the file cut short?)",
            vertices.len()
        ));
    }
    let welded = objects_with_faces > 1;
    if welded {
        weld(&mut vertices, &mut triangles);
    }
    Ok(ObjMesh {
        vertices,
        triangles,
        triangle_lines,
        welded,
    })
}

/// The 0-based vertex index of one face corner (`v`, `v/vt`, `v//vn`, `v/vt/vn`) when
/// `n_vertices` vertices have been read so far.
fn face_corner(tok: &str, n_vertices: usize) -> Result<u32, String> {
    let index = tok.split('/').next().unwrap_or("");
    let i: i64 = index
        .parse()
        .map_err(|_| format!("face corner {tok:?}: vertex index {index:?} is not an integer"))?;
    let resolved = if i > 0 {
        i - 1
    } else if i < 0 {
        n_vertices as i64 + i
    } else {
        return Err(format!(
            "face corner {tok:?}: vertex index 0 (OBJ indices start at 1)"
        ));
    };
    if resolved < 0 || resolved >= n_vertices as i64 {
        return Err(format!(
            "face corner {tok:?}: vertex {i} does not exist ({n_vertices} vertices read so far)"
        ));
    }
    Ok(resolved as u32)
}

/// Merges vertices at exactly the same position (first occurrence kept) and renumbers the
/// triangles; unused vertices are kept.
fn weld(vertices: &mut Vec<Vec3<f64>>, triangles: &mut [[u32; 3]]) {
    let mut first: HashMap<[u64; 3], u32> = HashMap::new();
    let mut remap = Vec::with_capacity(vertices.len());
    let mut kept = Vec::with_capacity(vertices.len());
    for v in vertices.iter() {
        // `+ 0.0` turns -0.0 into 0.0, so both weld.
        let key = [
            (v.x + 0.0).to_bits(),
            (v.y + 0.0).to_bits(),
            (v.z + 0.0).to_bits(),
        ];
        let id = *first.entry(key).or_insert_with(|| {
            kept.push(*v);
            (kept.len() - 1) as u32
        });
        remap.push(id);
    }
    for t in triangles.iter_mut() {
        for c in t.iter_mut() {
            *c = remap[*c as usize];
        }
    }
    *vertices = kept;
}

#[cfg(test)]
mod tests {
    use super::*;

    const CUBE: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 0 0 1\nv 1 0 1\nv 0 1 1\nv 1 1 1\n\
        f 1 5 7 3\nf 2 4 8 6\nf 1 2 6 5\nf 3 7 8 4\nf 1 3 4 2\nf 5 6 8 7\n";

    #[test]
    fn cube_reads_closed() {
        let m = parse_closed_mesh(CUBE).unwrap();
        assert_eq!((m.vertices().len(), m.triangles().len()), (8, 12));
    }

    #[test]
    fn corner_forms_and_negative_indices() {
        let text = CUBE.replace("f 1 5 7 3", "f 1/1 -4//2 7/3/4 -6");
        let m = parse_closed_mesh(&text).unwrap();
        assert_eq!(m.triangles()[0], [0, 4, 6]);
        assert_eq!(m.triangles()[1], [0, 6, 2]);
    }

    #[test]
    fn objects_are_welded() {
        // Two objects, each with its own copy of the eight corners.
        let (v, f) = CUBE.split_at(CUBE.find("f ").unwrap());
        let faces: Vec<&str> = f.lines().collect();
        let shift = |l: &str| {
            let ix: Vec<String> = l[2..]
                .split(' ')
                .map(|i| (i.parse::<u32>().unwrap() + 8).to_string())
                .collect();
            format!("f {}\n", ix.join(" "))
        };
        let second: String = faces[3..].iter().map(|l| shift(l)).collect();
        let text = format!("o a\n{v}{}\no b\n{v}{second}", faces[..3].join("\n") + "\n");
        let m = parse_closed_mesh(&text).unwrap();
        assert_eq!(m.vertices().len(), 8);
    }

    #[test]
    fn errors_name_the_line() {
        let e = parse_closed_mesh(&CUBE.replace("v 1 1 0", "v 1 x 0")).unwrap_err();
        assert!(e.starts_with("line 4: vertex coordinate y"), "{e}");
        let e = parse_closed_mesh(&CUBE.replace("f 3 7 8 4", "f 3 7 9 4")).unwrap_err();
        assert!(e.starts_with("line 12: face corner \"9\""), "{e}");
        let e = parse_closed_mesh(&CUBE.replace("f 3 7 8 4\n", "")).unwrap_err();
        assert!(e.starts_with("line 9: mesh is not closed"), "{e}");
        let cut = &CUBE[..CUBE.find("f ").unwrap()];
        let e = parse_closed_mesh(cut).unwrap_err();
        assert!(e.starts_with("no faces: 8 vertices"), "{e}");
    }
}
