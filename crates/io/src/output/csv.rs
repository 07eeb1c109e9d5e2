//! CSV output with full-precision numbers.

use std::path::Path;

use crate::OutputError;
use crate::atomic::write_atomic;

/// Formats `x` with the shortest text that parses back to exactly `x`: plain decimal for
/// `1e-5 ≤ |x| < 1e16` (and zero), scientific (`1.5e-7`) otherwise; `NaN`, `inf`, `-inf` for
/// non-finite values.
///
/// ```
/// use nurbspring_io::output::format_f64;
/// assert_eq!(format_f64(0.1), "0.1");
/// assert_eq!(format_f64(2.0), "2");
/// assert_eq!(format_f64(1.0 / 3.0).parse::<f64>().unwrap(), 1.0 / 3.0);
/// assert_eq!(format_f64(1e-300), "1e-300");
/// assert_eq!(format_f64(-6.02e23), "-6.02e23");
/// ```
pub fn format_f64(x: f64) -> String {
    let a = x.abs();
    if !x.is_finite() || a == 0.0 || (1e-5..1e16).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// Quotes a CSV field when it contains a comma, quote or line break (RFC 4180).
fn quote(field: &str) -> String {
    if field.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", field.replace('"', "\"\""))
    } else {
        field.to_string()
    }
}

/// Writes a CSV file: one header line, then one line per row, numbers formatted with
/// [`format_f64`] (exact round trip). Every row must have as many values as the header has
/// names, and every value finite (NaN and infinities are refused, naming the row and column);
/// otherwise nothing is written and the error names the row.
///
/// ```
/// # let dir = tempfile::tempdir().unwrap();
/// let path = dir.path().join("z.csv");
/// let rows = (0..3).map(|i| vec![0.08 * i as f64, 2.0 - 0.01 * i as f64]);
/// nurbspring_io::output::write_csv(&path, &["t", "z"], rows).unwrap();
/// assert_eq!(std::fs::read_to_string(&path).unwrap(), "t,z\n0,2\n0.08,1.99\n0.16,1.98\n");
/// ```
pub fn write_csv<I>(path: impl AsRef<Path>, header: &[&str], rows: I) -> Result<(), OutputError>
where
    I: IntoIterator<Item = Vec<f64>>,
{
    let path = path.as_ref();
    let mut text_rows = Vec::new();
    for (i, r) in rows.into_iter().enumerate() {
        if let Some((c, x)) = r.iter().enumerate().find(|(_, x)| !x.is_finite()) {
            return Err(OutputError::invalid(
                path,
                format!(
                    "row {i}, column {:?} is {}: non-finite values are never written",
                    header.get(c).copied().unwrap_or("?"),
                    format_f64(*x)
                ),
            ));
        }
        text_rows.push(r.into_iter().map(format_f64).collect::<Vec<_>>());
    }
    write_csv_text(path, header, text_rows)
}

/// Writes a CSV file whose fields are already text (for tables mixing names and numbers; use
/// [`format_f64`] for the numbers). Fields are quoted where needed.
pub fn write_csv_text<I>(
    path: impl AsRef<Path>,
    header: &[&str],
    rows: I,
) -> Result<(), OutputError>
where
    I: IntoIterator<Item = Vec<String>>,
{
    let path = path.as_ref();
    if header.is_empty() {
        return Err(OutputError::invalid(
            path,
            "a CSV file needs at least one column",
        ));
    }
    // Render first: a bad row must not leave a partial file behind.
    let mut text = String::new();
    text.push_str(
        &header
            .iter()
            .map(|h| quote(h))
            .collect::<Vec<_>>()
            .join(","),
    );
    text.push('\n');
    for (i, row) in rows.into_iter().enumerate() {
        if row.len() != header.len() {
            return Err(OutputError::invalid(
                path,
                format!(
                    "CSV row {i} has {} values but the header has {} columns ({})",
                    row.len(),
                    header.len(),
                    header.join(",")
                ),
            ));
        }
        text.push_str(&row.iter().map(|f| quote(f)).collect::<Vec<_>>().join(","));
        text.push('\n');
    }
    write_atomic(path, |w| w.write_all(text.as_bytes()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn format_round_trips(bits in any::<u64>()) {
            let x = f64::from_bits(bits);
            let s = format_f64(x);
            let y: f64 = s.parse().unwrap();
            if x.is_nan() {
                prop_assert!(y.is_nan());
            } else {
                prop_assert_eq!(y.to_bits(), x.to_bits(), "{} -> {}", x, s);
            }
            prop_assert!(s.len() <= 24, "{}", s);
        }
    }

    #[test]
    fn values_read_back_exactly() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("v.csv");
        let rows = vec![
            vec![0.1, 1.0 / 3.0, -0.0],
            vec![1e-310, f64::MAX, f64::MIN_POSITIVE],
            vec![-f64::MAX, 2.7225, 0.8661],
        ];
        write_csv(&p, &["a", "b", "c"], rows.clone()).unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next(), Some("a,b,c"));
        for (line, row) in lines.zip(&rows) {
            let back: Vec<f64> = line.split(',').map(|s| s.parse().unwrap()).collect();
            for (b, r) in back.iter().zip(row) {
                assert!(
                    b.to_bits() == r.to_bits() || (b.is_nan() && r.is_nan()),
                    "{line}"
                );
            }
        }
    }

    #[test]
    fn ragged_row_is_refused_and_nothing_written() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bad.csv");
        let err = write_csv(&p, &["t", "z"], vec![vec![0.0, 1.0], vec![1.0]]).unwrap_err();
        assert!(err.to_string().contains("row 1 has 1 values"), "{err}");
        assert!(!p.exists());
    }

    #[test]
    fn non_finite_values_are_refused_naming_row_and_column() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("nan.csv");
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let err = write_csv(&p, &["t", "z"], vec![vec![0.0, 1.0], vec![1.0, bad]]).unwrap_err();
            assert!(err.to_string().contains("row 1, column \"z\""), "{err}");
            assert!(!p.exists());
        }
    }

    #[test]
    fn text_fields_are_quoted() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t.csv");
        write_csv_text(
            &p,
            &["name", "value"],
            vec![vec!["a,b".to_string(), "say \"hi\"".to_string()]],
        )
        .unwrap();
        assert_eq!(
            std::fs::read_to_string(&p).unwrap(),
            "name,value\n\"a,b\",\"say \"\"hi\"\"\"\n"
        );
    }
}
