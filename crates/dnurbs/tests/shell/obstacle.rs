//! The shell obstacle course (Belytschko et al. 1985; Kirchhoff–Love values from Kiendl et
//! al. 2009): linear analysis, i.e. the tangent at rest.

use nurbspring_dnurbs::{Loads, PointLoad, ShellMaterial};

use crate::support::{self, *};

/// Scordelis–Lo roof: R = 25, L = 50, 80° arc, t = 0.25, E = 4.32e8, ν = 0, self-weight 90
/// per unit area, rigid diaphragms at the ends (u_y = u_z = 0), free straight edges. The
/// vertical displacement of the free edge's midpoint converges to 0.3006 for Kirchhoff–Love
/// shells (0.3024 in the older tables, with shear deformation).
fn scordelis_lo(degree: usize, spans: usize) -> f64 {
    let deg = std::f64::consts::PI / 180.0;
    let coarse = cylinder_sector(25.0, 50.0, 50.0 * deg, 130.0 * deg);
    let s = refined(&coarse, degree, (spans, spans));
    let p0 = coordinates(&s);
    let mut linear = Vec::new();
    for k in row_u(&s, 0).into_iter().chain(row_u(&s, s.n_u() - 1)) {
        linear.push(hold(k, 1, &p0));
        linear.push(hold(k, 2, &p0));
    }
    // The rigid translation along the axis: a symmetric pair keeps its mean.
    let (a, b) = (s.index(1, 0), s.index(s.n_u() - 2, 0));
    linear.push(nurbspring_dnurbs::LinearConstraint {
        terms: vec![(3 * a, 1.0), (3 * b, 1.0)],
        rhs: p0[3 * a] + p0[3 * b],
    });
    let material = ShellMaterial {
        young: 4.32e8,
        poisson: 0.0,
        thickness: 0.25,
        density: 1.0,
        gamma: 0.0,
    };
    let loads = Loads {
        distributed: [0.0, 0.0, -90.0],
        ..Loads::default()
    };
    let model = shell_model(s, material, loads, linear, vec![]);
    let p = model.linearized_steady_state().unwrap();
    -displacement(&model, 0.5, 0.0, &p)[2]
}

#[test]
fn scordelis_lo_roof_converges_to_the_kirchhoff_love_value() {
    let mut last = 0.0;
    for (degree, spans) in [(2, 4), (3, 8), (4, 16)] {
        let w = scordelis_lo(degree, spans);
        eprintln!("Scordelis–Lo p = {degree}, {spans}²: {w:.6}");
        last = w;
    }
    assert!((last - 0.3006).abs() < 0.01 * 0.3006, "{last}");
}

/// Pinched cylinder with rigid diaphragms: R = 300, L = 600, t = 3, E = 3e6, ν = 0.3, two
/// opposite radial loads F = 1 at midspan; one octant with three symmetry planes, F/4. The
/// displacement under the load is 1.8248e-5.
fn pinched_cylinder(degree: usize, spans: usize) -> f64 {
    let coarse = cylinder_sector(300.0, 300.0, 0.0, std::f64::consts::FRAC_PI_2);
    let s = refined(&coarse, degree, (spans, spans));
    let p0 = coordinates(&s);
    let (nu, nv) = (s.n_u(), s.n_v());
    let mut linear = Vec::new();
    // Midspan x = 0: symmetry (normal x).
    linear.extend(symmetry(&row_u(&s, 0), &row_u(&s, 1), 0, &p0));
    // Angle 0 (the plane z = 0) and angle 90° (the plane y = 0).
    linear.extend(symmetry(&row_v(&s, 0), &row_v(&s, 1), 2, &p0));
    linear.extend(symmetry(&row_v(&s, nv - 1), &row_v(&s, nv - 2), 1, &p0));
    // Diaphragm at x = L/2.
    for k in row_u(&s, nu - 1) {
        linear.push(hold(k, 1, &p0));
        linear.push(hold(k, 2, &p0));
    }
    let material = ShellMaterial {
        young: 3e6,
        poisson: 0.3,
        thickness: 3.0,
        density: 1.0,
        gamma: 0.0,
    };
    let loads = Loads {
        point: vec![PointLoad {
            u: 0.0,
            v: 1.0,
            force: [0.0, 0.0, -0.25],
        }],
        ..Loads::default()
    };
    let model = shell_model(s, material, loads, linear, vec![]);
    let p = model.linearized_steady_state().unwrap();
    -displacement(&model, 0.0, 1.0, &p)[2]
}

#[test]
fn pinched_cylinder_converges_to_the_reference() {
    let mut last = 0.0;
    for (degree, spans) in [(3, 8), (4, 16), (4, 32)] {
        let w = pinched_cylinder(degree, spans);
        eprintln!("pinched cylinder p = {degree}, {spans}²: {w:.6e}");
        last = w;
    }
    assert!((last - 1.8248e-5).abs() < 0.01 * 1.8248e-5, "{last}");
}

/// Pinched hemisphere with an 18° hole: R = 10, t = 0.04, E = 6.825e7, ν = 0.3, four radial
/// loads F = 2 alternating in sign on the equator; a quarter with two symmetry planes, F/2 at
/// each load. The radial displacement under the load is about 0.0935 for Kirchhoff–Love shells
/// (0.094 in the older tables).
fn pinched_hemisphere(degree: usize, spans: usize) -> f64 {
    let deg = std::f64::consts::PI / 180.0;
    let coarse = sphere_zone(10.0, 72.0 * deg);
    let s = refined(&coarse, degree, (spans, spans));
    let p0 = coordinates(&s);
    let nv = s.n_v();
    let mut linear = Vec::new();
    // Longitude 0 (plane y = 0) and 90° (plane x = 0).
    linear.extend(symmetry(&row_v(&s, 0), &row_v(&s, 1), 1, &p0));
    linear.extend(symmetry(&row_v(&s, nv - 1), &row_v(&s, nv - 2), 0, &p0));
    // The rigid translation along z: the loads are self-equilibrated.
    linear.push(hold(0, 2, &p0));
    let material = ShellMaterial {
        young: 6.825e7,
        poisson: 0.3,
        thickness: 0.04,
        density: 1.0,
        gamma: 0.0,
    };
    let loads = Loads {
        point: vec![
            PointLoad {
                u: 0.0,
                v: 0.0,
                force: [1.0, 0.0, 0.0],
            },
            PointLoad {
                u: 0.0,
                v: 1.0,
                force: [0.0, -1.0, 0.0],
            },
        ],
        ..Loads::default()
    };
    let model = shell_model(s, material, loads, linear, vec![]);
    let p = model.linearized_steady_state().unwrap();
    displacement(&model, 0.0, 0.0, &p)[0]
}

#[test]
fn pinched_hemisphere_converges_to_the_kirchhoff_love_value() {
    let mut last = 0.0;
    for (degree, spans) in [(3, 8), (4, 16), (4, 32)] {
        let w = pinched_hemisphere(degree, spans);
        eprintln!("pinched hemisphere p = {degree}, {spans}²: {w:.6}");
        last = w;
    }
    let _ = support::tol::ROTATION;
    assert!((last - 0.0935).abs() < 0.01 * 0.0935, "{last}");
}
