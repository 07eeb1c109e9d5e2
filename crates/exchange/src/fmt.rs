//! Number formatting shared by the writers.

/// Rust's shortest round-trip text of a finite double (`{:?}`): `1.0`, `0.1`, `1e-7`, `-0.0`.
/// Parsing it with a correctly rounding reader gives back the same bits.
pub(crate) fn shortest(x: f64) -> String {
    format!("{x:?}")
}

/// The shortest round-trip text as an IGES real constant: always a decimal point, exponent
/// letter `E` (`1.0E-7`, `0.5`, `-2.0E300`).
pub(crate) fn iges_real(x: f64) -> String {
    let s = shortest(x);
    match s.split_once('e') {
        Some((mantissa, exponent)) => {
            if mantissa.contains('.') {
                format!("{mantissa}E{exponent}")
            } else {
                format!("{mantissa}.0E{exponent}")
            }
        }
        None => s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn iges_reals_keep_a_point_and_round_trip() {
        for (x, t) in [
            (1.0, "1.0"),
            (0.1, "0.1"),
            (1e-7, "1.0E-7"),
            (1.5e300, "1.5E300"),
            (-0.0, "-0.0"),
            (f64::MIN_POSITIVE / 4.0, "5.562684646268003E-309"),
        ] {
            assert_eq!(iges_real(x), t);
            assert_eq!(t.parse::<f64>().unwrap().to_bits(), x.to_bits());
        }
    }
}
