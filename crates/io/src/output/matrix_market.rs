//! Matrix Market exchange format (NIST): `coordinate real general`, `coordinate real
//! symmetric` (lower triangle stored) and `array real general` (dense, column-major; used for
//! vectors). Indices in the file are 1-based; numbers are written with
//! [`super::format_f64`] and so read back exactly.

use std::io::Write;
use std::path::Path;

use nurbspring_linalg::SparseMatrix;

use super::format_f64;
use crate::OutputError;
use crate::atomic::write_atomic;

/// Relative tolerance, against the largest entry, under which `A_ij` and `A_ji` count as equal
/// for [`write_matrix_market_symmetric`].
const SYMMETRY_TOLERANCE: f64 = 1e-12;

/// Writes the comment lines (each prefixed by `%`).
fn write_comment(w: &mut dyn Write, comment: &str) -> std::io::Result<()> {
    for line in comment.lines() {
        writeln!(w, "%{}{line}", if line.is_empty() { "" } else { " " })?;
    }
    Ok(())
}

/// Writes `a` as `%%MatrixMarket matrix coordinate real general`: every stored entry, 1-based,
/// in column-major order. `comment` (possibly several lines) goes after the banner; use it to
/// state the dof ordering.
///
/// ```
/// # let dir = tempfile::tempdir().unwrap();
/// use nurbspring_linalg::SparseMatrix;
/// let a = SparseMatrix::from_triplets(2, 3, &[(0, 0, 1.5), (1, 2, -2.0)]).unwrap();
/// let path = dir.path().join("a.mtx");
/// nurbspring_io::output::write_matrix_market(&path, &a, "example").unwrap();
/// assert_eq!(
///     std::fs::read_to_string(&path).unwrap(),
///     "%%MatrixMarket matrix coordinate real general\n% example\n2 3 2\n1 1 1.5\n2 3 -2\n"
/// );
/// assert_eq!(nurbspring_io::output::read_matrix_market(&path).unwrap(), a);
/// ```
pub fn write_matrix_market(
    path: impl AsRef<Path>,
    a: &SparseMatrix,
    comment: &str,
) -> Result<(), OutputError> {
    let path = path.as_ref();
    check_finite(path, a.triplets().map(|(i, j, v)| ((i, j), v)))?;
    write_atomic(path, |w| {
        writeln!(w, "%%MatrixMarket matrix coordinate real general")?;
        write_comment(w, comment)?;
        writeln!(w, "{} {} {}", a.nrows(), a.ncols(), a.nnz())?;
        for (i, j, v) in a.triplets() {
            writeln!(w, "{} {} {}", i + 1, j + 1, format_f64(v))?;
        }
        Ok(())
    })
}

/// Writes a symmetric matrix as `%%MatrixMarket matrix coordinate real symmetric`: only the
/// non-zero entries with `row ≥ col` are stored (explicit zeros of the sparsity pattern are
/// left out, so an all-zero matrix is a file with 0 entries). Refuses (writing nothing) a matrix that is not square
/// or whose upper triangle differs from its lower one by more than `1e-12` times its largest
/// entry, naming the worst entry.
pub fn write_matrix_market_symmetric(
    path: impl AsRef<Path>,
    a: &SparseMatrix,
    comment: &str,
) -> Result<(), OutputError> {
    let path = path.as_ref();
    if a.nrows() != a.ncols() {
        return Err(OutputError::invalid(
            path,
            format!(
                "a symmetric Matrix Market file needs a square matrix, got {} x {}",
                a.nrows(),
                a.ncols()
            ),
        ));
    }
    check_finite(path, a.triplets().map(|(i, j, v)| ((i, j), v)))?;
    let scale = a.triplets().fold(0.0_f64, |m, (_, _, v)| m.max(v.abs()));
    let mut worst: Option<(usize, usize, f64, f64)> = None;
    let mut worst_diff = SYMMETRY_TOLERANCE * scale;
    for (i, j, v) in a.triplets() {
        if i == j {
            continue;
        }
        let t = a.get(j, i);
        let diff = (v - t).abs();
        if diff > worst_diff || diff.is_nan() {
            worst_diff = if diff.is_nan() { f64::INFINITY } else { diff };
            worst = Some((i, j, v, t));
        }
    }
    if let Some((i, j, v, t)) = worst {
        return Err(OutputError::invalid(
            path,
            format!(
                "matrix is not symmetric: A[{i}][{j}] = {v} but A[{j}][{i}] = {t} \
                 (largest entry {scale})"
            ),
        ));
    }
    let lower: Vec<(usize, usize, f64)> = a
        .triplets()
        .filter(|&(i, j, v)| i >= j && v != 0.0)
        .collect();
    write_atomic(path, |w| {
        writeln!(w, "%%MatrixMarket matrix coordinate real symmetric")?;
        write_comment(w, comment)?;
        writeln!(w, "{} {} {}", a.nrows(), a.ncols(), lower.len())?;
        for (i, j, v) in &lower {
            writeln!(w, "{} {} {}", i + 1, j + 1, format_f64(*v))?;
        }
        Ok(())
    })
}

/// Writes a dense `nrows × ncols` matrix given in column-major order as
/// `%%MatrixMarket matrix array real general`.
pub fn write_matrix_market_array(
    path: impl AsRef<Path>,
    nrows: usize,
    ncols: usize,
    column_major: &[f64],
    comment: &str,
) -> Result<(), OutputError> {
    let path = path.as_ref();
    if nrows.checked_mul(ncols) != Some(column_major.len()) {
        return Err(OutputError::invalid(
            path,
            format!(
                "a {nrows} x {ncols} array needs {} values, got {}",
                nrows.saturating_mul(ncols),
                column_major.len()
            ),
        ));
    }
    check_finite(
        path,
        column_major
            .iter()
            .enumerate()
            .map(|(k, &v)| ((k % nrows.max(1), k / nrows.max(1)), v)),
    )?;
    write_atomic(path, |w| {
        writeln!(w, "%%MatrixMarket matrix array real general")?;
        write_comment(w, comment)?;
        writeln!(w, "{nrows} {ncols}")?;
        for v in column_major {
            writeln!(w, "{}", format_f64(*v))?;
        }
        Ok(())
    })
}

/// Writes a vector as an `n × 1` Matrix Market array.
pub fn write_matrix_market_vector(
    path: impl AsRef<Path>,
    x: &[f64],
    comment: &str,
) -> Result<(), OutputError> {
    write_matrix_market_array(path, x.len(), 1, x, comment)
}

/// Refuses (naming the 1-based entry) a NaN or infinite value: never written to a file.
fn check_finite(
    path: &Path,
    entries: impl Iterator<Item = ((usize, usize), f64)>,
) -> Result<(), OutputError> {
    for ((i, j), v) in entries {
        if !v.is_finite() {
            return Err(OutputError::invalid(
                path,
                format!(
                    "entry ({}, {}) is {v}: non-finite values are never written",
                    i + 1,
                    j + 1
                ),
            ));
        }
    }
    Ok(())
}

/// What the banner line says.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Layout {
    Coordinate,
    Array,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Symmetry {
    General,
    Symmetric,
    SkewSymmetric,
}

/// A parsed Matrix Market file before conversion.
struct Parsed {
    layout: Layout,
    nrows: usize,
    ncols: usize,
    /// Coordinate: the stored triplets (0-based, symmetric parts expanded). Array: empty.
    triplets: Vec<(usize, usize, f64)>,
    /// Array: the values, column-major (symmetric storage expanded). Coordinate: empty.
    dense: Vec<f64>,
}

/// Refuses sizes that would make the reader allocate absurd amounts of memory.
const MAX_ENTRIES: usize = 1 << 31;

fn parse_file(path: &Path) -> Result<Parsed, OutputError> {
    let text = std::fs::read_to_string(path).map_err(|e| OutputError::io(path, e))?;
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l));
    let (_, banner) = lines
        .next()
        .ok_or_else(|| OutputError::parse(path, 1, "empty file"))?;
    let words: Vec<String> = banner
        .split_whitespace()
        .map(|w| w.to_ascii_lowercase())
        .collect();
    if words.len() != 5 || words[0] != "%%matrixmarket" || words[1] != "matrix" {
        return Err(OutputError::parse(
            path,
            1,
            format!(
                "expected a `%%MatrixMarket matrix <layout> <field> <symmetry>` banner, got `{banner}`"
            ),
        ));
    }
    let layout = match words[2].as_str() {
        "coordinate" => Layout::Coordinate,
        "array" => Layout::Array,
        other => {
            return Err(OutputError::parse(
                path,
                1,
                format!("unknown layout `{other}`"),
            ));
        }
    };
    match words[3].as_str() {
        "real" | "integer" | "double" => {}
        other => {
            return Err(OutputError::parse(
                path,
                1,
                format!("field `{other}` is not supported (real or integer only)"),
            ));
        }
    }
    let symmetry = match words[4].as_str() {
        "general" => Symmetry::General,
        "symmetric" => Symmetry::Symmetric,
        "skew-symmetric" => Symmetry::SkewSymmetric,
        other => {
            return Err(OutputError::parse(
                path,
                1,
                format!("symmetry `{other}` is not supported"),
            ));
        }
    };
    let mut data = lines.filter(|(_, l)| {
        let t = l.trim_start();
        !t.is_empty() && !t.starts_with('%')
    });
    let (size_line, size_text) = data
        .next()
        .ok_or_else(|| OutputError::parse(path, 1, "missing size line"))?;
    let size: Vec<usize> = size_text
        .split_whitespace()
        .map(|s| s.parse::<usize>())
        .collect::<Result<_, _>>()
        .map_err(|e| {
            OutputError::parse(path, size_line, format!("bad size line `{size_text}`: {e}"))
        })?;
    let expected_words = if layout == Layout::Coordinate { 3 } else { 2 };
    if size.len() != expected_words {
        return Err(OutputError::parse(
            path,
            size_line,
            format!("the size line needs {expected_words} integers, got `{size_text}`"),
        ));
    }
    let (nrows, ncols) = (size[0], size[1]);
    if symmetry != Symmetry::General && nrows != ncols {
        return Err(OutputError::parse(
            path,
            size_line,
            format!("a symmetric matrix must be square, got {nrows} x {ncols}"),
        ));
    }
    let parse_value = |line: usize, s: &str| -> Result<f64, OutputError> {
        s.parse::<f64>()
            .map_err(|e| OutputError::parse(path, line, format!("bad value `{s}`: {e}")))
    };
    let mut parsed = Parsed {
        layout,
        nrows,
        ncols,
        triplets: Vec::new(),
        dense: Vec::new(),
    };
    match layout {
        Layout::Coordinate => {
            let nnz = size[2];
            if nnz > MAX_ENTRIES {
                return Err(OutputError::parse(
                    path,
                    size_line,
                    format!("{nnz} entries is too many"),
                ));
            }
            let mut count = 0;
            for (line, l) in data {
                let w: Vec<&str> = l.split_whitespace().collect();
                if w.len() != 3 {
                    return Err(OutputError::parse(
                        path,
                        line,
                        format!("expected `row col value`, got `{l}`"),
                    ));
                }
                let index = |s: &str, n: usize, what: &str| -> Result<usize, OutputError> {
                    match s.parse::<usize>() {
                        Ok(k) if (1..=n).contains(&k) => Ok(k - 1),
                        _ => Err(OutputError::parse(
                            path,
                            line,
                            format!("{what} index `{s}` is not in 1..={n}"),
                        )),
                    }
                };
                let i = index(w[0], nrows, "row")?;
                let j = index(w[1], ncols, "column")?;
                let v = parse_value(line, w[2])?;
                if symmetry != Symmetry::General && i < j {
                    return Err(OutputError::parse(
                        path,
                        line,
                        format!(
                            "entry ({}, {}) lies above the diagonal of a symmetric file",
                            i + 1,
                            j + 1
                        ),
                    ));
                }
                parsed.triplets.push((i, j, v));
                if i != j {
                    match symmetry {
                        Symmetry::General => {}
                        Symmetry::Symmetric => parsed.triplets.push((j, i, v)),
                        Symmetry::SkewSymmetric => parsed.triplets.push((j, i, -v)),
                    }
                }
                count += 1;
            }
            if count != nnz {
                return Err(OutputError::parse(
                    path,
                    size_line,
                    format!("the size line announces {nnz} entries but the file has {count}"),
                ));
            }
        }
        Layout::Array => {
            let total = nrows
                .checked_mul(ncols)
                .filter(|&t| t <= MAX_ENTRIES)
                .ok_or_else(|| {
                    OutputError::parse(path, size_line, format!("{nrows} x {ncols} is too large"))
                })?;
            let mut values = Vec::new();
            for (line, l) in data {
                for s in l.split_whitespace() {
                    values.push(parse_value(line, s)?);
                }
            }
            let stored = match symmetry {
                Symmetry::General => total,
                Symmetry::Symmetric => nrows * (nrows + 1) / 2,
                Symmetry::SkewSymmetric => nrows * nrows.saturating_sub(1) / 2,
            };
            if values.len() != stored {
                return Err(OutputError::parse(
                    path,
                    size_line,
                    format!(
                        "a {nrows} x {ncols} array needs {stored} values, the file has {}",
                        values.len()
                    ),
                ));
            }
            if symmetry == Symmetry::General {
                parsed.dense = values;
            } else {
                // Lower triangle, column by column.
                let mut dense = vec![0.0; total];
                let mut it = values.into_iter();
                for j in 0..ncols {
                    let start = if symmetry == Symmetry::Symmetric {
                        j
                    } else {
                        j + 1
                    };
                    for i in start..nrows {
                        let v = it.next().unwrap_or(0.0);
                        dense[j * nrows + i] = v;
                        dense[i * nrows + j] = if symmetry == Symmetry::Symmetric {
                            v
                        } else {
                            -v
                        };
                    }
                }
                parsed.dense = dense;
            }
        }
    }
    Ok(parsed)
}

/// Reads a Matrix Market file (`coordinate` or `array`; `real` or `integer`; `general`,
/// `symmetric` or `skew-symmetric`) into a sparse matrix. Symmetric storage is expanded to both
/// triangles; an array becomes a sparse matrix holding all its (also zero) entries. Errors
/// name the line.
pub fn read_matrix_market(path: impl AsRef<Path>) -> Result<SparseMatrix, OutputError> {
    let path = path.as_ref();
    let p = parse_file(path)?;
    let triplets = match p.layout {
        Layout::Coordinate => p.triplets,
        Layout::Array => p
            .dense
            .iter()
            .enumerate()
            .map(|(k, &v)| (k % p.nrows.max(1), k / p.nrows.max(1), v))
            .collect(),
    };
    SparseMatrix::from_triplets(p.nrows, p.ncols, &triplets).map_err(|source| OutputError::Linalg {
        path: path.to_path_buf(),
        source,
    })
}

/// Reads a Matrix Market `array` file: `(nrows, ncols, values in column-major order)`. A
/// vector written by [`write_matrix_market_vector`] comes back as `(n, 1, x)`.
pub fn read_matrix_market_array(
    path: impl AsRef<Path>,
) -> Result<(usize, usize, Vec<f64>), OutputError> {
    let path = path.as_ref();
    let p = parse_file(path)?;
    if p.layout != Layout::Array {
        return Err(OutputError::parse(
            path,
            1,
            "expected an `array` file, found `coordinate`",
        ));
    }
    Ok((p.nrows, p.ncols, p.dense))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> SparseMatrix {
        SparseMatrix::from_triplets(
            4,
            4,
            &[
                (0, 0, 4.0),
                (1, 0, 1.0 / 3.0),
                (0, 1, 1.0 / 3.0),
                (1, 1, 2.5e-17),
                (3, 2, -7.25),
                (2, 3, -7.25),
                (3, 3, 1e300),
            ],
        )
        .unwrap()
    }

    #[test]
    fn general_round_trip_is_exact() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("k.mtx");
        let a = sample();
        write_matrix_market(&p, &a, "stiffness\nordering: [x0, y0, z0, x1, ...]").unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        assert!(
            text.starts_with(
                "%%MatrixMarket matrix coordinate real general\n% stiffness\n% ordering"
            )
        );
        assert_eq!(read_matrix_market(&p).unwrap(), a);
    }

    #[test]
    fn symmetric_round_trip_stores_lower_triangle() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("s.mtx");
        let a = sample();
        write_matrix_market_symmetric(&p, &a, "").unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        assert!(text.contains("\n4 4 5\n"), "{text}");
        assert_eq!(read_matrix_market(&p).unwrap(), a);
    }

    #[test]
    fn symmetric_writer_leaves_out_explicit_zeros() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("z.mtx");
        let a = SparseMatrix::from_triplets(
            3,
            3,
            &[
                (0, 0, 2.0),
                (1, 0, 0.0),
                (0, 1, 0.0),
                (2, 1, -1.0),
                (1, 2, -1.0),
                (2, 2, 0.0),
            ],
        )
        .unwrap();
        write_matrix_market_symmetric(&p, &a, "").unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        assert_eq!(
            text,
            "%%MatrixMarket matrix coordinate real symmetric\n3 3 2\n1 1 2\n3 2 -1\n"
        );
        let back = read_matrix_market(&p).unwrap();
        for i in 0..3 {
            for j in 0..3 {
                assert_eq!(back.get(i, j), a.get(i, j), "({i}, {j})");
            }
        }
        // An all-zero pattern (D with γ = 0) is a file with no entries.
        let zero = SparseMatrix::from_triplets(2, 2, &[(0, 0, 0.0), (1, 1, 0.0)]).unwrap();
        write_matrix_market_symmetric(&p, &zero, "").unwrap();
        assert_eq!(
            std::fs::read_to_string(&p).unwrap(),
            "%%MatrixMarket matrix coordinate real symmetric\n2 2 0\n"
        );
    }

    #[test]
    fn symmetric_writer_refuses_unsymmetric_matrix() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("u.mtx");
        let a = SparseMatrix::from_triplets(2, 2, &[(0, 1, 1.0), (1, 0, 2.0)]).unwrap();
        let err = write_matrix_market_symmetric(&p, &a, "").unwrap_err();
        assert!(err.to_string().contains("not symmetric"), "{err}");
        assert!(!p.exists());
        let r = SparseMatrix::from_triplets(2, 3, &[(0, 1, 1.0)]).unwrap();
        assert!(write_matrix_market_symmetric(&p, &r, "").is_err());
    }

    #[test]
    fn vector_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("x.mtx");
        let x = vec![0.1, -2.0, 1e-320, 3.0];
        write_matrix_market_vector(&p, &x, "free dofs").unwrap();
        let (n, m, back) = read_matrix_market_array(&p).unwrap();
        assert_eq!((n, m), (4, 1));
        assert_eq!(back, x);
        let s = read_matrix_market(&p).unwrap();
        assert_eq!((s.nrows(), s.ncols()), (4, 1));
        assert_eq!(s.get(1, 0), -2.0);
    }

    #[test]
    fn malformed_files_name_the_line() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bad.mtx");
        let cases = [
            ("", "empty file"),
            (
                "%%MatrixMarket matrix coordinate complex general\n1 1 1\n1 1 1\n",
                "complex",
            ),
            (
                "%%MatrixMarket matrix coordinate real general\n2 2 1\n3 1 1.0\n",
                ":3:",
            ),
            (
                "%%MatrixMarket matrix coordinate real general\n2 2 2\n1 1 1.0\n",
                "announces 2",
            ),
            (
                "%%MatrixMarket matrix coordinate real general\n2 2 1\n1 1 abc\n",
                "bad value `abc`",
            ),
            (
                "%%MatrixMarket matrix array real general\n2 2\n1\n2\n3\n",
                "needs 4 values",
            ),
        ];
        for (text, needle) in cases {
            std::fs::write(&p, text).unwrap();
            let err = read_matrix_market(&p).unwrap_err();
            assert!(err.to_string().contains(needle), "{text:?}: {err}");
        }
    }
}
