//! Figures: SVG text content, PNG decoding and non-blankness, non-finite input.

use nurbspring_io::plot::{
    PlotOptions, Series, SeriesStyle, plot_series, plot_series_with, plot_spectrum,
};

/// Where to put figures: a temporary folder, or `$NURBSPRING_KEEP_PLOTS` to look at them.
fn out_dir() -> (Option<tempfile::TempDir>, std::path::PathBuf) {
    match std::env::var_os("NURBSPRING_KEEP_PLOTS") {
        Some(d) => {
            std::fs::create_dir_all(&d).unwrap();
            (None, d.into())
        }
        None => {
            let t = tempfile::tempdir().unwrap();
            let p = t.path().to_path_buf();
            (Some(t), p)
        }
    }
}

fn trajectories() -> Vec<Series> {
    let t: Vec<f64> = (0..=50).map(|k| 0.08 * k as f64).collect();
    vec![
        Series::line(
            "D-NURBS",
            t.iter()
                .map(|&t| (t, 2.0 - 0.05 * (1.3 * t).sin()))
                .collect(),
        ),
        Series {
            name: "MSM (symplectic Euler)".into(),
            points: t
                .iter()
                .map(|&t| (t, 2.0 - 0.045 * (1.2 * t).sin()))
                .collect(),
            style: SeriesStyle::LinePoints,
        },
    ]
}

#[test]
fn svg_contains_title_labels_and_series_names() {
    let (_keep, dir) = out_dir();
    let p = dir.join("trajectory.svg");
    let s = plot_series(&p, "Central node z(t)", "t [s]", "z", &trajectories()).unwrap();
    assert_eq!(s.skipped, 0);
    assert_eq!(s.drawn, 102);
    let svg = std::fs::read_to_string(&p).unwrap();
    assert!(svg.starts_with("<svg"), "{}", &svg[..50]);
    for needle in [
        "Central node z(t)",
        "t [s]",
        "D-NURBS",
        "MSM (symplectic Euler)",
    ] {
        assert!(svg.contains(needle), "missing {needle}");
    }
}

/// Decodes a PNG and returns (width, height, RGB pixels).
fn decode(p: &std::path::Path) -> (u32, u32, Vec<[u8; 3]>) {
    let bytes = std::fs::read(p).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    let img = image::load_from_memory_with_format(&bytes, image::ImageFormat::Png)
        .unwrap()
        .to_rgb8();
    let (w, h) = img.dimensions();
    (w, h, img.pixels().map(|p| p.0).collect())
}

#[test]
fn png_decodes_and_has_text_and_curves() {
    let (_keep, dir) = out_dir();
    let p = dir.join("trajectory.png");
    plot_series(&p, "Central node z(t)", "t [s]", "z", &trajectories()).unwrap();
    let (w, h, px) = decode(&p);
    assert_eq!((w, h), (1024, 640));
    let dark = |c: &[u8; 3]| c.iter().all(|&v| v < 100);
    // The caption (black text) occupies the top band.
    let title_dark = (0..40 * w as usize).filter(|&k| dark(&px[k])).count();
    assert!(
        title_dark > 100,
        "no caption text rendered ({title_dark} dark pixels)"
    );
    // Both series colours appear.
    let count = |rgb: [u8; 3]| px.iter().filter(|&&c| c == rgb).count();
    assert!(count([31, 119, 180]) > 200);
    assert!(count([255, 127, 14]) > 200);
}

#[test]
fn non_finite_points_are_skipped_and_reported() {
    let (_keep, dir) = out_dir();
    let mut s = trajectories();
    s[0].points[3].1 = f64::NAN;
    s[1].points[7].0 = f64::INFINITY;
    s.push(Series::line(
        "diverged",
        vec![(0.0, f64::NAN), (1.0, f64::NEG_INFINITY)],
    ));
    for ext in ["svg", "png"] {
        let p = dir.join(format!("nonfinite.{ext}"));
        let summary = plot_series(&p, "with gaps", "t", "z", &s).unwrap();
        assert_eq!(summary.skipped, 4);
        assert_eq!(summary.drawn, 100);
        if ext == "svg" {
            let svg = std::fs::read_to_string(&p).unwrap();
            assert!(svg.contains("with gaps (4 non-finite points omitted)"));
        }
    }
    // Nothing drawable at all still gives a figure with axes.
    let p = dir.join("empty.png");
    let summary = plot_series(
        &p,
        "nothing",
        "t",
        "z",
        &[Series::line("nan", vec![(f64::NAN, 1.0)])],
    )
    .unwrap();
    assert_eq!(summary.drawn, 0);
    assert_eq!(decode(&p).0, 1024);
}

#[test]
fn log_scale_mass_scan() {
    let (_keep, dir) = out_dir();
    let candidates: Vec<(f64, f64)> = (1..=20)
        .map(|k| (1e-3 * k as f64, 10f64.powf(-(k as f64 - 10.0).abs() / 3.0)))
        .chain([(0.5, 0.0), (0.6, -1.0)])
        .collect();
    let mut opts = PlotOptions::new("Mass candidates", "m", "RMS error");
    opts.log_y = true;
    for ext in ["svg", "png"] {
        let p = dir.join(format!("mass_scan.{ext}"));
        let s = plot_series_with(&p, &opts, &[Series::points("RMS", candidates.clone())]).unwrap();
        assert_eq!((s.drawn, s.skipped), (20, 2));
    }
    let svg = std::fs::read_to_string(dir.join("mass_scan.svg")).unwrap();
    assert!(svg.contains("non-finite or non-positive"));
    // On log axes both ways (masses over decades): a non-positive mass is skipped too, and
    // each decade of x is labelled.
    let over_decades: Vec<(f64, f64)> = (0..=12)
        .map(|k| (1e-6 * 10f64.powf(k as f64 / 4.0), 0.01 + 1e-3 * k as f64))
        .chain([(0.0, 0.02), (-1e-5, 0.02)])
        .collect();
    opts.log_x = true;
    let p = dir.join("both.svg");
    let s = plot_series_with(&p, &opts, &[Series::points("RMS", over_decades)]).unwrap();
    assert_eq!((s.drawn, s.skipped), (13, 2));
    let texts = svg_texts(&std::fs::read_to_string(&p).unwrap());
    for label in ["1.0e-5", "1.0e-4", "0.0010"] {
        assert!(texts.iter().any(|t| t == label), "{label} not in {texts:?}");
    }
}

#[test]
fn spectrum_plot_has_both_sets() {
    let (_keep, dir) = out_dir();
    let dn = [0.8, 1.9, 2.5, 3.7];
    let msm = [0.7, 2.0, 2.4, f64::NAN, 4.2];
    for ext in ["svg", "png"] {
        let p = dir.join(format!("spectrum.{ext}"));
        let s = plot_spectrum(
            &p,
            "Eigenfrequencies",
            "ω [rad/s]",
            &[("D-NURBS", &dn), ("MSM", &msm)],
        )
        .unwrap();
        assert_eq!((s.drawn, s.skipped), (8, 1));
    }
    let svg = std::fs::read_to_string(dir.join("spectrum.svg")).unwrap();
    for needle in ["Eigenfrequencies", "D-NURBS", "MSM", "mode", "ω [rad/s]"] {
        assert!(svg.contains(needle), "missing {needle}");
    }
}

/// The texts of an SVG's `<text>` elements.
fn svg_texts(svg: &str) -> Vec<String> {
    svg.split("<text")
        .skip(1)
        .filter_map(|t| {
            let body = t.split_once('>')?.1;
            Some(body.split("</text>").next()?.trim().to_string())
        })
        .collect()
}

/// Thirty modes: the mode axis is labelled with whole numbers only.
#[test]
fn spectrum_mode_axis_has_integer_labels() {
    let (_keep, dir) = out_dir();
    let omega: Vec<f64> = (1..=30).map(|k| 100.0 * k as f64).collect();
    let p = dir.join("spectrum30.svg");
    plot_spectrum(
        &p,
        "Eigenfrequencies",
        "omega [rad/s]",
        &[("D-NURBS", &omega)],
    )
    .unwrap();
    let texts = svg_texts(&std::fs::read_to_string(&p).unwrap());
    let numbers: Vec<f64> = texts.iter().filter_map(|t| t.parse::<f64>().ok()).collect();
    // Mode labels lie in 1..=30; the omega labels are multiples of 100 or more.
    let modes: Vec<&String> = texts
        .iter()
        .filter(|t| t.parse::<f64>().is_ok_and(|x| x > 0.0 && x <= 31.0))
        .collect();
    assert!(modes.len() >= 4, "{texts:?}");
    for m in &modes {
        assert!(
            m.parse::<u32>().is_ok(),
            "mode label {m:?} is not an integer: {texts:?}"
        );
    }
    assert!(numbers.iter().any(|&x| x >= 100.0), "{texts:?}");
}

/// PNG lines are anti-aliased: the ink of a straight 2-pixel line (its coverage summed over
/// each pixel column) is the same all along it, where an aliased line steps between 1 and 3
/// pixels.
#[test]
fn png_lines_are_anti_aliased() {
    let (_keep, dir) = out_dir();
    let p = dir.join("diagonal.png");
    let line = Series::line(
        "line",
        (0..=10).map(|k| (k as f64, 0.7 * k as f64)).collect(),
    );
    plot_series(&p, "", "x", "y", &[line]).unwrap();
    let (w, h, px) = decode(&p);
    // Coverage α of a pixel blended from white towards the first colour (31, 119, 180).
    let alpha = |c: &[u8; 3]| {
        let a = (255.0 - f64::from(c[0])) / 224.0;
        let fits = (f64::from(c[1]) - (255.0 - 136.0 * a)).abs() < 12.0
            && (f64::from(c[2]) - (255.0 - 75.0 * a)).abs() < 12.0;
        if fits && a > 0.15 { a.min(1.0) } else { 0.0 }
    };
    // Columns well inside the plot, away from the grid lines (which hide part of the line).
    let mut ink = Vec::new();
    for x in (200..800).step_by(7) {
        let column: Vec<f64> = (0..h as usize)
            .map(|y| alpha(&px[y * w as usize + x]))
            .collect();
        // A vertical grid line greys most of its column.
        let grey = (0..h as usize)
            .filter(|&y| {
                let c = px[y * w as usize + x];
                c[0] == c[1] && c[1] == c[2] && c[0] < 250
            })
            .count();
        let grid = grey > h as usize / 2;
        if !grid {
            ink.push(column.iter().sum::<f64>());
        }
    }
    let n = ink.len() as f64;
    let mean = ink.iter().sum::<f64>() / n;
    let sd = (ink.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n).sqrt();
    assert!(ink.len() > 40, "{ink:?}");
    assert!(sd <= 0.1 * mean, "ink per column {mean} ± {sd}: {ink:?}");
}

#[test]
fn bad_extension_and_size_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let err = plot_series(dir.path().join("x.jpg"), "t", "x", "y", &[]).unwrap_err();
    assert!(err.to_string().contains(".svg or .png"), "{err}");
    let mut o = PlotOptions::new("t", "x", "y");
    o.width = 10;
    assert!(plot_series_with(dir.path().join("x.png"), &o, &[]).is_err());
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}
