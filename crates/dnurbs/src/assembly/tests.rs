//! Unit tests of `assembly`.

use super::*;
use nurbspring_geom::GaussLegendre;
use nurbspring_geom::{KnotVector, NurbsCurve, NurbsSurface};
use nurbspring_linalg::AssemblyPattern;
use proptest::prelude::*;

/// A clamped knot vector of degree `p` on `[0, 1]` whose interior knots are `interior`
/// (sorted, with repetitions up to `p`), spread unevenly.
fn knots(p: usize, interior: &[usize]) -> KnotVector {
    let mut k = vec![0.0; p + 1];
    for &x in interior {
        k.push(f64::from(x as u32 + 1) / 7.0 + 0.01 * f64::from(x as u32 % 3));
    }
    k.extend(std::iter::repeat_n(1.0, p + 1));
    KnotVector::try_new(k, p).unwrap()
}

fn surface(ku: KnotVector, kv: KnotVector, weight: f64) -> Geometry {
    let (gu, gv) = (ku.greville(), kv.greville());
    let pts: Vec<[f64; 3]> = gu
        .iter()
        .enumerate()
        .flat_map(|(i, &u)| {
            gv.iter().enumerate().map(move |(j, &v)| {
                [
                    2.0 * u + 0.1 * v,
                    0.7 * v,
                    0.3 * ((i * 3 + j * 5) % 4) as f64,
                ]
            })
        })
        .collect();
    let n = pts.len();
    Geometry::Surface(NurbsSurface::try_new(ku, kv, pts, vec![weight; n]).unwrap())
}

fn curve(k: KnotVector, weight: f64) -> Geometry {
    let pts: Vec<[f64; 3]> = k
        .greville()
        .iter()
        .enumerate()
        .map(|(i, &u)| [u, 0.2 * (i % 3) as f64, 0.1 * u * u])
        .collect();
    let n = pts.len();
    Geometry::Curve(NurbsCurve::try_new(k, pts, vec![weight; n]).unwrap())
}

fn material(mask: u8) -> Material {
    let on = |bit: u8, x: f64| if mask & (1 << bit) != 0 { x } else { 0.0 };
    Material {
        mu: 1.3,
        gamma: 0.0,
        alpha11: on(0, 0.9),
        alpha22: on(1, 1.7),
        beta11: on(2, 0.031),
        beta12: on(3, 0.047),
        beta22: on(4, 0.023),
    }
}

fn curve_material(mask: u8) -> Material {
    Material {
        alpha22: 0.0,
        beta12: 0.0,
        beta22: 0.0,
        ..material(mask)
    }
}

/// `max |a − b| / max(max |b|, floor)` (patterns may differ: `S ⊗ I_3` stores no
/// off-diagonal zeros of its 3 × 3 blocks, the dof-level pattern does). The floor keeps a
/// matrix that is zero in exact arithmetic (β terms of degree 1) from dividing round-off by
/// round-off.
fn relative_difference(a: &SparseMatrix, b: &SparseMatrix, floor: f64) -> f64 {
    let diff = max_abs(&SparseMatrix::linear_combination(1.0, a, -1.0, b).unwrap());
    let scale = max_abs(b).max(floor);
    if scale > 0.0 { diff / scale } else { diff }
}

fn max_abs(m: &SparseMatrix) -> f64 {
    m.values().iter().fold(0.0f64, |s, x| s.max(x.abs()))
}

/// The Kronecker form against the Gauss-point kernel and against the dof-level general
/// assembler (`S ⊗ I_3`), all on the same pattern; returns the largest relative difference.
fn kronecker_against_general(geometry: &Geometry, material: &Material, g: usize) -> f64 {
    let scalar = ScalarAssembler::new(geometry, g).unwrap();
    let fast = scalar.run_kronecker(geometry, material);
    let gauss = scalar.run_gauss(geometry, material, Integration::Parameter);
    let loads = Loads {
        gravity: [0.5, -9.81, 0.0],
        distributed: [0.25, 0.0, 1.5],
        point: Vec::new(),
        edges: Vec::new(),
    };
    let general = GeneralAssembler::new(geometry, g, 3).unwrap().run(
        geometry,
        material,
        &loads,
        Integration::Parameter,
        None,
    );
    assert!(fast.unit_mass.same_pattern(&gauss.unit_mass));
    assert!(fast.stiffness.same_pattern(&gauss.stiffness));
    // The stiffness is compared on the scale of the mass when it is smaller.
    let floor = max_abs(&gauss.unit_mass);
    let mut worst = relative_difference(&fast.unit_mass, &gauss.unit_mass, 0.0)
        .max(relative_difference(
            &fast.stiffness,
            &gauss.stiffness,
            floor,
        ))
        .max(relative_difference(
            &fast.unit_mass.kron_identity(3),
            &general.unit_mass,
            0.0,
        ))
        .max(relative_difference(
            &fast.stiffness.kron_identity(3),
            &general.stiffness,
            floor,
        ));
    // Basis integrals are at most the parameter area (partition of unity).
    let density = loads.density(material.mu);
    for (k, (a, b)) in fast
        .basis_integrals
        .iter()
        .zip(&gauss.basis_integrals)
        .enumerate()
    {
        worst = worst.max((a - b).abs());
        for x in 0..3 {
            worst = worst.max((a * density[x] - general.force[3 * k + x]).abs() / 10.0);
        }
    }
    worst
}

#[test]
fn kronecker_form_equals_the_general_assembler_on_a_bicubic_patch() {
    let g = surface(knots(3, &[0, 1, 2, 3, 4]), knots(3, &[1, 3]), 1.0);
    assert!(kronecker_against_general(&g, &material(0b11111), 4) < 1e-13);
}

#[test]
fn kronecker_form_equals_the_general_assembler_with_repeated_knots_and_weights() {
    // Interior knots of multiplicity p (C0 lines), uniform weights ≠ 1, too few points.
    let g = surface(knots(2, &[1, 1, 4]), knots(3, &[2, 2, 2, 5]), 2.5);
    for g_points in [1, 2, 3, 5] {
        for mask in [0, 0b00001, 0b01000, 0b10100, 0b11111] {
            let e = kronecker_against_general(&g, &material(mask), g_points);
            assert!(e < 1e-13, "{g_points} points, terms {mask:05b}: {e:e}");
        }
    }
}

#[test]
fn kronecker_form_equals_the_general_assembler_on_curves() {
    let c = curve(knots(3, &[0, 2, 2, 5]), 0.8);
    for mask in [0, 0b00001, 0b00100, 0b00101] {
        let e = kronecker_against_general(&c, &curve_material(mask), 4);
        assert!(e < 1e-13, "terms {mask:05b}: {e:e}");
    }
}

/// The pattern built from the spans equals the sorted pattern of every element's local
/// entries (the construction it replaces), for scalar and dof-level matrices.
#[test]
fn tensor_pattern_equals_the_sorted_element_pattern() {
    let cases = [
        surface(knots(2, &[1, 1, 4]), knots(3, &[2, 2, 2, 5]), 1.0),
        surface(knots(1, &[0, 3, 3]), knots(4, &[]), 1.0),
        curve(knots(3, &[0, 2, 2, 5]), 1.0),
    ];
    for geometry in &cases {
        let ((p, q), n_v) = (geometry.degrees(), geometry.net_shape().1);
        let (ku, kv, _) = knots_of(geometry);
        let spans = |k: &[f64], deg: usize| -> Vec<usize> {
            (deg..k.len() - deg - 1)
                .filter(|&s| k[s] < k[s + 1])
                .collect()
        };
        let sv = if geometry.is_curve() {
            vec![0]
        } else {
            spans(&kv, q)
        };
        for m in [1, 3, 4] {
            let mut entries = Vec::new();
            for &su in &spans(&ku, p) {
                for &s in &sv {
                    let mut dofs = Vec::new();
                    for i in su - p..=su {
                        for j in s - q..=s {
                            for x in 0..m {
                                dofs.push((i * n_v + j) * m + x);
                            }
                        }
                    }
                    for &r in &dofs {
                        for &c in &dofs {
                            entries.push((r, c));
                        }
                    }
                }
            }
            let layout = TensorLayout::new(geometry, 3, m).unwrap();
            let n = layout.pattern.n();
            let sorted = AssemblyPattern::new(n, n, &entries).unwrap().zero_matrix();
            assert_eq!(layout.pattern.col_ptr(), sorted.col_ptr());
            assert_eq!(layout.pattern.row_idx(), sorted.row_idx());
        }
    }
}

/// Dense `S_M`, `S_K` by brute force: Gauss points of every element, the geometry's own
/// Jacobian (nurbspring-geom, NURBS Book A4.4) at each, every pair of control points.
fn dense_reference(
    geometry: &Geometry,
    material: &Material,
    g: usize,
    integration: Integration,
) -> (Vec<f64>, Vec<f64>) {
    let n = geometry.n_control_points();
    let rule = GaussLegendre::new(g).unwrap();
    let (ku, kv, _) = knots_of(geometry);
    let spans = |k: &[f64], deg: usize| -> Vec<(f64, f64)> {
        (deg..k.len() - deg - 1)
            .filter(|&s| k[s] < k[s + 1])
            .map(|s| (k[s], k[s + 1]))
            .collect()
    };
    let (p, q) = geometry.degrees();
    let sv = if geometry.is_curve() {
        vec![(0.0, 0.0)]
    } else {
        spans(&kv, q)
    };
    let coef = material.stiffness_by_slot();
    let (mut m, mut k) = (vec![0.0; n * n], vec![0.0; n * n]);
    for &(ua, ub) in &spans(&ku, p) {
        for &(va, vb) in &sv {
            let vs: Vec<(f64, f64)> = if geometry.is_curve() {
                vec![(0.0, 1.0)]
            } else {
                rule.mapped(va, vb).collect()
            };
            for (u, wu) in rule.mapped(ua, ub) {
                for &(v, wv) in &vs {
                    let jac = geometry.jacobian(u, v, 2, false).unwrap();
                    let wt = match integration {
                        Integration::Parameter => wu * wv,
                        Integration::Area => wu * wv * area_factor(geometry, &jac),
                    };
                    for (a, &i) in jac.indices.iter().enumerate() {
                        for (b, &j) in jac.indices.iter().enumerate() {
                            m[i * n + j] += wt * jac.r[a][0] * jac.r[b][0];
                            for s in 1..6 {
                                k[i * n + j] += wt * coef[s] * jac.r[a][s] * jac.r[b][s];
                            }
                        }
                    }
                }
            }
        }
    }
    (m, k)
}

/// `max |a − dense| / max |dense|` over every entry (zeros outside the pattern included).
fn against_dense(a: &SparseMatrix, dense: &[f64]) -> f64 {
    let n = a.nrows();
    let scale = dense.iter().fold(0.0f64, |s, x| s.max(x.abs()));
    let mut worst = 0.0f64;
    for i in 0..n {
        for j in 0..n {
            worst = worst.max((a.get(i, j) - dense[i * n + j]).abs());
        }
    }
    worst / scale
}

/// The Gauss-point kernel (rational basis from the span tables and the quotient rule)
/// equals a dense assembly through the geometry's own Jacobian, on rational surfaces and
/// curves, over the parameter domain and the area.
#[test]
fn gauss_point_kernel_equals_a_dense_reference_on_rational_geometry() {
    let mut s = surface(knots(2, &[1, 1, 4]), knots(3, &[2, 5]), 1.0);
    let mut c = curve(knots(3, &[0, 2, 2, 5]), 1.0);
    for geometry in [&mut s, &mut c] {
        let w: Vec<f64> = (0..geometry.n_control_points())
            .map(|k| 0.6 + 0.15 * ((k * 7) % 5) as f64)
            .collect();
        let mut p = geometry.coordinates(false);
        let mut full = Vec::new();
        for (chunk, &wk) in p.chunks_exact_mut(3).zip(&w) {
            full.extend_from_slice(chunk);
            full.push(wk);
        }
        *geometry = geometry.with_coordinates(&full, true).unwrap();
    }
    for geometry in [&s, &c] {
        assert!(!geometry.has_uniform_weights());
        let material = if geometry.is_curve() {
            curve_material(0b11111)
        } else {
            material(0b11111)
        };
        for integration in [Integration::Parameter, Integration::Area] {
            for g in [2, 4] {
                let values = ScalarAssembler::new(geometry, g).unwrap().run(
                    geometry,
                    &material,
                    integration,
                );
                let (m, k) = dense_reference(geometry, &material, g, integration);
                let e =
                    against_dense(&values.unit_mass, &m).max(against_dense(&values.stiffness, &k));
                assert!(e < 1e-13, "{integration:?}, {g} points: {e:e}");
            }
        }
    }
}

/// (knots, degree) of a direction: the Kronecker form equals the Gauss-point kernel for
/// random degrees, interior knots with repetitions, terms and rules.
fn direction() -> impl Strategy<Value = KnotVector> {
    (1usize..=4)
        .prop_flat_map(|p| (Just(p), proptest::collection::vec(0usize..6, 0..6)))
        .prop_map(|(p, mut interior)| {
            interior.sort_unstable();
            // At most p repetitions of an interior knot.
            let mut kept: Vec<usize> = Vec::new();
            for x in interior {
                if kept.iter().filter(|&&y| y == x).count() < p {
                    kept.push(x);
                }
            }
            knots(p, &kept)
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    #[test]
    fn kronecker_form_equals_the_general_assembler(
        ku in direction(), kv in direction(), mask in 0u8..32, g in 1usize..7,
        weight in 0.5f64..3.0,
    ) {
        let geometry = surface(ku, kv, weight);
        let e = kronecker_against_general(&geometry, &material(mask), g);
        prop_assert!(e < 1e-12, "relative difference {:e}", e);
    }
}
