//! Wavefront OBJ: vertices, polygonal faces (quads of a surface tessellation) and line
//! elements (`l a b`, the springs of a lattice). Indices are 0-based in memory and 1-based in
//! the file.

use std::path::Path;

use super::format_f64;
use crate::OutputError;
use crate::atomic::write_atomic;

/// A polygon mesh with optional line elements, as written to and read from an OBJ file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ObjMesh {
    /// Vertex positions.
    pub vertices: Vec<[f64; 3]>,
    /// Faces as lists of 0-based vertex indices (3 or more each).
    pub faces: Vec<Vec<usize>>,
    /// Line elements as pairs of 0-based vertex indices.
    pub lines: Vec<[usize; 2]>,
    /// Texture coordinates `(u, v)`, one per vertex, or empty (written as `vt`).
    pub uvs: Vec<[f64; 2]>,
    /// Unit normals, one per vertex, or empty (written as `vn`).
    pub normals: Vec<[f64; 3]>,
}

impl ObjMesh {
    /// The quad mesh of a tessellated surface: `points[i * n_v + j]` is the point at the `i`-th
    /// u and `j`-th v sample; one quad `(i, j), (i+1, j), (i+1, j+1), (i, j+1)` per cell.
    /// Returns `None` when `points.len() != n_u * n_v`.
    ///
    /// ```
    /// use nurbspring_io::output::ObjMesh;
    /// let pts = vec![[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]];
    /// let m = ObjMesh::quad_grid(pts, 2, 2).unwrap();
    /// assert_eq!(m.faces, vec![vec![0, 2, 3, 1]]);
    /// ```
    pub fn quad_grid(points: Vec<[f64; 3]>, n_u: usize, n_v: usize) -> Option<Self> {
        if n_u.checked_mul(n_v) != Some(points.len()) {
            return None;
        }
        let mut faces = Vec::with_capacity(n_u.saturating_sub(1) * n_v.saturating_sub(1));
        for i in 0..n_u.saturating_sub(1) {
            for j in 0..n_v.saturating_sub(1) {
                let k = i * n_v + j;
                faces.push(vec![k, k + n_v, k + n_v + 1, k + 1]);
            }
        }
        Some(Self {
            vertices: points,
            faces,
            ..Self::default()
        })
    }

    /// A line lattice: nodes and springs (pairs of node indices).
    pub fn lattice(nodes: Vec<[f64; 3]>, springs: Vec<[usize; 2]>) -> Self {
        Self {
            vertices: nodes,
            lines: springs,
            ..Self::default()
        }
    }

    /// Checks that every index refers to a vertex and every face has at least 3 corners.
    fn check(&self) -> Result<(), String> {
        let n = self.vertices.len();
        for (what, len) in [
            ("texture coordinates", self.uvs.len()),
            ("normals", self.normals.len()),
        ] {
            if len != 0 && len != n {
                return Err(format!(
                    "{len} {what} for {n} vertices (one per vertex or none)"
                ));
            }
        }
        for (f, face) in self.faces.iter().enumerate() {
            if face.len() < 3 {
                return Err(format!(
                    "face {f} has {} vertices, at least 3 needed",
                    face.len()
                ));
            }
            if let Some(&k) = face.iter().find(|&&k| k >= n) {
                return Err(format!(
                    "face {f} refers to vertex {k}, but there are {n} vertices"
                ));
            }
        }
        for (l, line) in self.lines.iter().enumerate() {
            if let Some(&k) = line.iter().find(|&&k| k >= n) {
                return Err(format!(
                    "line {l} refers to vertex {k}, but there are {n} vertices"
                ));
            }
        }
        Ok(())
    }
}

/// Writes `mesh` as an OBJ file (`v x y z`, `vt u v`, `vn x y z`, `f a b c …` (`a/a/a` with
/// texture coordinates and normals), `l a b`, 1-based), with `comment` as `#` lines at the top.
/// Numbers read back exactly.
pub fn write_obj(path: impl AsRef<Path>, mesh: &ObjMesh, comment: &str) -> Result<(), OutputError> {
    let path = path.as_ref();
    mesh.check().map_err(|m| OutputError::invalid(path, m))?;
    write_atomic(path, |w| {
        for line in comment.lines() {
            writeln!(w, "# {line}")?;
        }
        for v in &mesh.vertices {
            writeln!(
                w,
                "v {} {} {}",
                format_f64(v[0]),
                format_f64(v[1]),
                format_f64(v[2])
            )?;
        }
        for t in &mesh.uvs {
            writeln!(w, "vt {} {}", format_f64(t[0]), format_f64(t[1]))?;
        }
        for n in &mesh.normals {
            writeln!(
                w,
                "vn {} {} {}",
                format_f64(n[0]),
                format_f64(n[1]),
                format_f64(n[2])
            )?;
        }
        let (uv, normal) = (!mesh.uvs.is_empty(), !mesh.normals.is_empty());
        for face in &mesh.faces {
            write!(w, "f")?;
            for k in face {
                let k = k + 1;
                match (uv, normal) {
                    (false, false) => write!(w, " {k}")?,
                    (true, false) => write!(w, " {k}/{k}")?,
                    (false, true) => write!(w, " {k}//{k}")?,
                    (true, true) => write!(w, " {k}/{k}/{k}")?,
                }
            }
            writeln!(w)?;
        }
        for [a, b] in &mesh.lines {
            writeln!(w, "l {} {}", a + 1, b + 1)?;
        }
        Ok(())
    })
}

/// Reads the subset of OBJ that [`write_obj`] produces, plus what common exporters add:
/// `v` (extra w ignored), `f` with `a/b/c` references (only the vertex index kept, negative
/// indices counted from the end), `l` with two or more vertices (split into segments). Other
/// statements (`vn`, `vt`, `o`, `g`, `s`, `usemtl`, `mtllib`) are skipped. Errors name the line.
pub fn read_obj(path: impl AsRef<Path>) -> Result<ObjMesh, OutputError> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|e| OutputError::io(path, e))?;
    let mut mesh = ObjMesh::default();
    for (n, raw) in text.lines().enumerate() {
        let line = n + 1;
        let content = raw.split('#').next().unwrap_or("").trim();
        let mut words = content.split_whitespace();
        let Some(tag) = words.next() else { continue };
        let rest: Vec<&str> = words.collect();
        let index = |s: &str, count: usize| -> Result<usize, OutputError> {
            let first = s.split('/').next().unwrap_or("");
            let k: i64 = first
                .parse()
                .map_err(|e| OutputError::parse(path, line, format!("bad index `{s}`: {e}")))?;
            let resolved = if k > 0 { k - 1 } else { count as i64 + k };
            if k == 0 || resolved < 0 || resolved >= count as i64 {
                return Err(OutputError::parse(
                    path,
                    line,
                    format!("index {k} does not refer to one of the {count} vertices read so far"),
                ));
            }
            Ok(resolved as usize)
        };
        match tag {
            "v" => {
                if rest.len() < 3 {
                    return Err(OutputError::parse(
                        path,
                        line,
                        format!("`v` needs 3 coordinates: `{raw}`"),
                    ));
                }
                let mut p = [0.0; 3];
                for (c, s) in p.iter_mut().zip(&rest) {
                    *c = s.parse().map_err(|e| {
                        OutputError::parse(path, line, format!("bad coordinate `{s}`: {e}"))
                    })?;
                }
                mesh.vertices.push(p);
            }
            "f" => {
                if rest.len() < 3 {
                    return Err(OutputError::parse(
                        path,
                        line,
                        format!("`f` needs 3 or more vertices: `{raw}`"),
                    ));
                }
                let face = rest
                    .iter()
                    .map(|s| index(s, mesh.vertices.len()))
                    .collect::<Result<Vec<_>, _>>()?;
                mesh.faces.push(face);
            }
            "l" => {
                if rest.len() < 2 {
                    return Err(OutputError::parse(
                        path,
                        line,
                        format!("`l` needs 2 or more vertices: `{raw}`"),
                    ));
                }
                let ids = rest
                    .iter()
                    .map(|s| index(s, mesh.vertices.len()))
                    .collect::<Result<Vec<_>, _>>()?;
                mesh.lines.extend(ids.windows(2).map(|w| [w[0], w[1]]));
            }
            _ => {}
        }
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn surface_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("s.obj");
        let pts: Vec<[f64; 3]> = (0..3)
            .flat_map(|i| (0..4).map(move |j| [i as f64 * 0.1, j as f64 / 3.0, 2.0]))
            .collect();
        let mesh = ObjMesh::quad_grid(pts, 3, 4).unwrap();
        assert_eq!(mesh.faces.len(), 6);
        write_obj(&p, &mesh, "surface\n3 x 4").unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        assert!(text.starts_with("# surface\n# 3 x 4\nv 0 0 2\n"));
        assert!(text.contains("\nf 1 5 6 2\n"));
        assert_eq!(read_obj(&p).unwrap(), mesh);
        assert!(ObjMesh::quad_grid(vec![[0.0; 3]; 5], 2, 3).is_none());
    }

    #[test]
    fn lattice_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("l.obj");
        let mesh = ObjMesh::lattice(
            vec![[0.0, 0.0, 2.0], [1.5, 0.0, 2.0], [1.5, 2.5, 2.0]],
            vec![[0, 1], [1, 2], [0, 2]],
        );
        write_obj(&p, &mesh, "").unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        assert!(text.ends_with("l 1 2\nl 2 3\nl 1 3\n"), "{text}");
        assert_eq!(read_obj(&p).unwrap(), mesh);
    }

    #[test]
    fn reader_handles_common_syntax_and_errors() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("x.obj");
        std::fs::write(
            &p,
            "o thing\nv 0 0 0 1\nv 1 0 0\nv 0 1 0 # comment\nvn 0 0 1\nf 1//1 2//1 -1//1\nl 1 2 3\n",
        )
        .unwrap();
        let m = read_obj(&p).unwrap();
        assert_eq!(m.vertices.len(), 3);
        assert_eq!(m.faces, vec![vec![0, 1, 2]]);
        assert_eq!(m.lines, vec![[0, 1], [1, 2]]);
        std::fs::write(&p, "v 0 0 0\nf 1 2 3\n").unwrap();
        let err = read_obj(&p).unwrap_err();
        assert!(err.to_string().contains(":2:"), "{err}");
        let bad = ObjMesh::lattice(vec![[0.0; 3]], vec![[0, 1]]);
        assert!(write_obj(&p, &bad, "").is_err());
    }
}
