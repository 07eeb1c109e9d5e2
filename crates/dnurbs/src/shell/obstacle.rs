//! The shell benchmarks as models (docs/shell.md): the linear obstacle course of Belytschko et
//! al. (1985) and the geometrically nonlinear problems tabulated by Sze, Liu and Lo (2004), each
//! on an exact NURBS geometry refined to a degree and a number of spans, with its probe point and
//! reference value. Used by the tests, `examples/shell_convergence.rs` and the benchmarks.

use nurbspring_geom::{BSplineBasis, KnotVector, NurbsSurface};

use crate::{
    Constraints, DnurbsError, DnurbsModel, DnurbsOptions, Edge, EdgeCondition, EdgeConstraint,
    EdgeLoad, Geometry, LinearConstraint, Loads, PointLoad, ShellMaterial,
};

/// A benchmark: the model, the parameters of the point whose displacement is compared, the
/// component compared (0, 1, 2 for x, y, z; its sign flipped when `negate`) and the reference.
pub struct Benchmark {
    /// The shell model.
    pub model: DnurbsModel,
    /// `(u, v)` of the probe.
    pub probe: (f64, f64),
    /// The displacement component compared.
    pub component: usize,
    /// Compare `−u_component` instead.
    pub negate: bool,
    /// The reference value of the compared displacement.
    pub reference: f64,
    /// The constraints the model was built with.
    pub constraints: Constraints,
}

impl Benchmark {
    /// The same benchmark with the discretization options `options` (e.g. a Gauss rule of
    /// `p + 1` points, as Kratos integrates).
    pub fn with_options(self, options: DnurbsOptions) -> Result<Self, DnurbsError> {
        let model = DnurbsModel::kirchhoff_love(
            self.model.geometry().clone(),
            *self.model.shell().expect("a shell").material(),
            self.model.loads().clone(),
            &self.constraints,
            options,
        )?;
        Ok(Self { model, ..self })
    }

    /// The compared displacement at the state `p`.
    pub fn displacement(&self, p: &[f64]) -> Result<f64, DnurbsError> {
        let (u, v) = self.probe;
        let a = self.model.point(u, v, p)?;
        let b = self.model.point(u, v, self.model.p0())?;
        let d = a[self.component] - b[self.component];
        Ok(if self.negate { -d } else { d })
    }
}

/// `coarse` elevated to `degree` in both directions and split into `spans` equal spans per
/// direction (a Bézier patch on `[0, 1]²`; exact: the geometry does not move).
pub fn refined(
    coarse: &NurbsSurface,
    degree: usize,
    spans: (usize, usize),
) -> Result<NurbsSurface, DnurbsError> {
    let (pu, pv) = (coarse.basis_u().degree(), coarse.basis_v().degree());
    let (e, _) = coarse.elevate_degree(degree.saturating_sub(pu), degree.saturating_sub(pv))?;
    let inner = |n: usize| -> Vec<f64> { (1..n).map(|k| k as f64 / n as f64).collect() };
    Ok(e.refine_knots(&inner(spans.0), &inner(spans.1))?.0)
}

/// A flat rectangle `[0, a] × [0, b]` in the plane z = 0 (a bilinear Bézier patch).
pub fn rectangle(a: f64, b: f64) -> NurbsSurface {
    let k = KnotVector::try_new(vec![0., 0., 1., 1.], 1).expect("a valid knot vector");
    let pts = vec![[0., 0., 0.], [0., b, 0.], [a, 0., 0.], [a, b, 0.]];
    NurbsSurface::try_new(k.clone(), k, pts, vec![1.0; 4]).expect("a valid patch")
}

/// A cylindrical sector: axis x over `[0, length]`, radius `r`, the arc from angle `a0` to `a1`
/// (less than π apart) in the y–z plane, angles from +y towards +z; u along x (linear), v along
/// the arc (one rational quadratic segment).
pub fn cylinder_sector(r: f64, length: f64, a0: f64, a1: f64) -> NurbsSurface {
    let half = 0.5 * (a1 - a0);
    let mid = 0.5 * (a0 + a1);
    let arc = [
        [r * a0.cos(), r * a0.sin()],
        [r / half.cos() * mid.cos(), r / half.cos() * mid.sin()],
        [r * a1.cos(), r * a1.sin()],
    ];
    let w = [1.0, half.cos(), 1.0];
    let mut pts = Vec::new();
    let mut weights = Vec::new();
    for x in [0.0, length] {
        for (c, &wk) in arc.iter().zip(&w) {
            pts.push([x, c[0], c[1]]);
            weights.push(wk);
        }
    }
    let ku = KnotVector::try_new(vec![0., 0., 1., 1.], 1).expect("a valid knot vector");
    let kv = KnotVector::try_new(vec![0., 0., 0., 1., 1., 1.], 2).expect("a valid knot vector");
    NurbsSurface::try_new(ku, kv, pts, weights).expect("a valid patch")
}

/// A quarter of a spherical zone of radius `r` about the z axis: u along the meridian from the
/// equator (latitude 0) to latitude `top` (< π/2), v along the parallel from longitude 0 (+x)
/// to 90° (+y). Biquadratic rational, one segment each way.
pub fn sphere_zone(r: f64, top: f64) -> NurbsSurface {
    let half = 0.5 * top;
    let meridian = [
        [r, 0.0],
        [r, r * half.tan()],
        [r * top.cos(), r * top.sin()],
    ];
    let wm = [1.0, half.cos(), 1.0];
    let parallel = [[1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    let wp = [1.0, std::f64::consts::FRAC_1_SQRT_2, 1.0];
    let mut pts = Vec::new();
    let mut weights = Vec::new();
    for (m, &w1) in meridian.iter().zip(&wm) {
        for (c, &w2) in parallel.iter().zip(&wp) {
            pts.push([m[0] * c[0], m[0] * c[1], m[1]]);
            weights.push(w1 * w2);
        }
    }
    let k = KnotVector::try_new(vec![0., 0., 0., 1., 1., 1.], 2).expect("a valid knot vector");
    NurbsSurface::try_new(k.clone(), k, pts, weights).expect("a valid patch")
}

/// An annulus `r_i ≤ r ≤ r_o`, `0 ≤ θ ≤ 2π`, cut along θ = 0, in the plane z = 0: u along r
/// (`degree`, `spans.0` spans), v along θ (`degree`, `spans.1` uniform spans) with the circle
/// interpolated at the Greville abscissae (a polynomial B-spline: a full circle has no rational
/// C¹ single-patch form; the interpolation error is below 1e-6 of the radius for 64 cubic spans).
pub fn slit_annulus(
    ri: f64,
    ro: f64,
    degree: usize,
    spans: (usize, usize),
) -> Result<NurbsSurface, DnurbsError> {
    let kv = KnotVector::clamped_uniform(degree, spans.1)?;
    let n = kv.n_basis();
    let g = kv.greville();
    let basis = BSplineBasis::new(kv.clone());
    let mut a = nurbspring_linalg::DenseMatrix::zeros(n, n);
    for (i, &t) in g.iter().enumerate() {
        for (j, value) in basis.all_values(t)?.into_iter().enumerate() {
            a[(i, j)] = value;
        }
    }
    let angle = |t: f64| 2.0 * std::f64::consts::PI * t;
    let cos: Vec<f64> = g.iter().map(|&t| angle(t).cos()).collect();
    let sin: Vec<f64> = g.iter().map(|&t| angle(t).sin()).collect();
    let (cx, cy) = (
        nurbspring_linalg::solve_dense(&a, &cos)?,
        nurbspring_linalg::solve_dense(&a, &sin)?,
    );
    let ku = KnotVector::try_new(vec![0., 0., 1., 1.], 1)?;
    let mut pts = Vec::new();
    for r in [ri, ro] {
        for j in 0..n {
            pts.push([r * cx[j], r * cy[j], 0.0]);
        }
    }
    let coarse = NurbsSurface::try_new(ku, kv, pts, vec![1.0; 2 * n])?;
    let (e, _) = coarse.elevate_degree(degree - 1, 0)?;
    let inner: Vec<f64> = (1..spans.0).map(|k| k as f64 / spans.0 as f64).collect();
    Ok(e.refine_knots(&inner, &[])?.0)
}

fn model(
    s: NurbsSurface,
    material: ShellMaterial,
    loads: Loads,
    constraints: Constraints,
) -> Result<DnurbsModel, DnurbsError> {
    DnurbsModel::kirchhoff_love(
        Geometry::Surface(s),
        material,
        loads,
        &constraints,
        DnurbsOptions::default(),
    )
}

fn edge(edge: Edge, condition: EdgeCondition) -> EdgeConstraint {
    EdgeConstraint { edge, condition }
}

/// The Scordelis–Lo roof: R = 25, L = 50, 80° of arc, t = 0.25, E = 4.32e8, ν = 0, self-weight
/// 90 per unit area, rigid diaphragms at the curved ends. A quarter: from the diaphragm (u = 0)
/// to midspan (u = 1, symmetry), from the free edge (v = 0, 50°) to the crown (v = 1, 90°,
/// symmetry). Compared: the vertical displacement of the free edge's midpoint, 0.3006 for
/// Kirchhoff–Love shells (0.3024 in the older tables).
pub fn scordelis_lo(degree: usize, spans: usize) -> Result<Benchmark, DnurbsError> {
    let deg = std::f64::consts::PI / 180.0;
    let s = refined(
        &cylinder_sector(25.0, 25.0, 50.0 * deg, 90.0 * deg),
        degree,
        (spans, spans),
    )?;
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
    let constraints = Constraints {
        edges: vec![
            edge(Edge::U0, EdgeCondition::Hold([false, true, true])),
            edge(Edge::U1, EdgeCondition::Symmetry),
            edge(Edge::V1, EdgeCondition::Symmetry),
        ],
        ..Constraints::default()
    };
    Ok(Benchmark {
        model: model(s, material, loads, constraints.clone())?,
        constraints,
        probe: (1.0, 0.0),
        component: 2,
        negate: true,
        reference: 0.3006,
    })
}

/// The whole Scordelis–Lo roof (the net of Kratos' runs in docs/benchmarks.md): the arc from
/// 50° (v = 0) to 130° (v = 1), x from 0 to 50, rigid diaphragms at both ends, the axial rigid
/// translation removed by the mirror pair of the free edge about midspan (`u_x` of the second
/// and second-to-last points of the row v = 0 opposite; the symmetric solution satisfies it, so
/// it carries no force). Compared: the vertical displacement at (0.5, 0).
pub fn scordelis_lo_roof(degree: usize, spans: usize) -> Result<Benchmark, DnurbsError> {
    let deg = std::f64::consts::PI / 180.0;
    let s = refined(
        &cylinder_sector(25.0, 50.0, 50.0 * deg, 130.0 * deg),
        degree,
        (spans, spans),
    )?;
    let (a, b) = (s.index(1, 0), s.index(s.n_u() - 2, 0));
    let (xa, xb) = (s.control_points()[a][0], s.control_points()[b][0]);
    let mut bench = scordelis_lo(degree, spans)?;
    let material = *bench.model.shell().expect("a shell").material();
    let loads = bench.model.loads().clone();
    let constraints = Constraints {
        edges: vec![
            edge(Edge::U0, EdgeCondition::Hold([false, true, true])),
            edge(Edge::U1, EdgeCondition::Hold([false, true, true])),
        ],
        linear: vec![LinearConstraint {
            terms: vec![(3 * a, 1.0), (3 * b, 1.0)],
            rhs: xa + xb,
        }],
        ..Constraints::default()
    };
    bench.model = model(s, material, loads, constraints.clone())?;
    bench.constraints = constraints;
    bench.probe = (0.5, 0.0);
    Ok(bench)
}

/// The pinched cylinder with rigid diaphragms: R = 300, L = 600, t = 3, E = 3e6, ν = 0.3, two
/// opposite radial loads F = 1 at midspan. An octant: from midspan (u = 0, symmetry) to the
/// diaphragm (u = 1), the arc from angle 0 (v = 0, symmetry) to 90° (v = 1, symmetry, the load
/// F/4). Compared: the radial displacement under the load, 1.8248e-5.
pub fn pinched_cylinder(degree: usize, spans: usize) -> Result<Benchmark, DnurbsError> {
    let s = refined(
        &cylinder_sector(300.0, 300.0, 0.0, std::f64::consts::FRAC_PI_2),
        degree,
        (spans, spans),
    )?;
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
    let constraints = Constraints {
        edges: vec![
            edge(Edge::U0, EdgeCondition::Symmetry),
            edge(Edge::U1, EdgeCondition::Hold([false, true, true])),
            edge(Edge::V0, EdgeCondition::Symmetry),
            edge(Edge::V1, EdgeCondition::Symmetry),
        ],
        ..Constraints::default()
    };
    Ok(Benchmark {
        model: model(s, material, loads, constraints.clone())?,
        constraints,
        probe: (0.0, 1.0),
        component: 2,
        negate: true,
        reference: 1.8248e-5,
    })
}

/// The hemisphere with an 18° hole: R = 10, t = 0.04, E = 6.825e7, ν = 0.3, four radial point
/// loads alternating in sign on the equator. A quarter (symmetry at longitudes 0 and 90°, the
/// z translation held at one equator point), `force` at each load point: outwards at
/// (R, 0, 0), inwards at (0, R, 0). Compared: the x displacement at (R, 0, 0).
pub fn hemisphere(degree: usize, spans: usize, force: f64) -> Result<Benchmark, DnurbsError> {
    let deg = std::f64::consts::PI / 180.0;
    let s = refined(&sphere_zone(10.0, 72.0 * deg), degree, (spans, spans))?;
    let z0 = s.control_points()[0][2];
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
                force: [force, 0.0, 0.0],
            },
            PointLoad {
                u: 0.0,
                v: 1.0,
                force: [0.0, -force, 0.0],
            },
        ],
        ..Loads::default()
    };
    let constraints = Constraints {
        edges: vec![
            edge(Edge::V0, EdgeCondition::Symmetry),
            edge(Edge::V1, EdgeCondition::Symmetry),
        ],
        // The loads are self-equilibrated: the rigid z translation is held at one point.
        linear: vec![LinearConstraint {
            terms: vec![(2, 1.0)],
            rhs: z0,
        }],
        ..Constraints::default()
    };
    Ok(Benchmark {
        model: model(s, material, loads, constraints.clone())?,
        constraints,
        probe: (0.0, 0.0),
        component: 0,
        negate: false,
        reference: 0.0935 * force,
    })
}

/// Sze et al. §3.1, the cantilever under end shear: a strip 10 × 1, t = 0.1, E = 1.2e6, ν = 0,
/// clamped at u = 0, a shear of `P_max = 4` spread over the tip edge. Compared: the tip's
/// deflection w at (1, 0.5) at the full load, 6.6996 (the elastica; Sze's table: 6.698).
pub fn sze_cantilever(degree: usize, spans: usize) -> Result<Benchmark, DnurbsError> {
    let s = refined(&rectangle(10.0, 1.0), degree, (spans, 1))?;
    let material = ShellMaterial {
        young: 1.2e6,
        poisson: 0.0,
        thickness: 0.1,
        density: 1.0,
        gamma: 0.0,
    };
    let loads = Loads {
        edges: vec![EdgeLoad {
            edge: Edge::U1,
            force: [0.0, 0.0, 4.0],
            moment: 0.0,
        }],
        ..Loads::default()
    };
    let constraints = Constraints {
        edges: vec![edge(Edge::U0, EdgeCondition::Clamped)],
        ..Constraints::default()
    };
    Ok(Benchmark {
        model: model(s, material, loads, constraints.clone())?,
        constraints,
        probe: (1.0, 0.5),
        component: 2,
        negate: false,
        reference: 6.6996,
    })
}

/// Sze et al. §3.3, the slit annular plate: R_i = 6, R_o = 10, t = 0.03, E = 21e6, ν = 0,
/// clamped along the slit's side θ = 0, a vertical line force of up to 0.8 per unit length along
/// the other side. Compared: w at the outer corner B (1, 1) at the full load, 17.528 (Sze's
/// table; w_A at (0, 1): 13.891).
pub fn slit_annular_plate(degree: usize, spans: (usize, usize)) -> Result<Benchmark, DnurbsError> {
    let s = slit_annulus(6.0, 10.0, degree, spans)?;
    let material = ShellMaterial {
        young: 21e6,
        poisson: 0.0,
        thickness: 0.03,
        density: 1.0,
        gamma: 0.0,
    };
    let loads = Loads {
        edges: vec![EdgeLoad {
            edge: Edge::V1,
            force: [0.0, 0.0, 0.8],
            moment: 0.0,
        }],
        ..Loads::default()
    };
    let constraints = Constraints {
        edges: vec![edge(Edge::V0, EdgeCondition::Clamped)],
        ..Constraints::default()
    };
    Ok(Benchmark {
        model: model(s, material, loads, constraints.clone())?,
        constraints,
        probe: (1.0, 1.0),
        component: 2,
        negate: false,
        reference: 17.528,
    })
}
