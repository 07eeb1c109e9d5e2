//! Small scenes for the unit tests.

use nurbspring_dnurbs::{Constraints, DnurbsOptions, Geometry, Loads, Material};
use nurbspring_msm::LatticeOptions;
use nurbspring_sim::IntegratorKind;

use crate::method::Method;
use crate::setup::{Config, FitOptions, InitialConditions, Setup, TimeSettings};

/// A paper-method setup on `geometry`: unit μ and α, the outer ring fixed, the paper's
/// spring classes on the default lattice, a short Newmark reference.
pub(crate) fn setup(geometry: Geometry) -> Setup {
    Setup::new(&config(geometry)).unwrap()
}

/// The configuration of [`setup`].
pub(crate) fn config(geometry: Geometry) -> Config {
    let alpha22 = if geometry.is_curve() { 0.0 } else { 1.0 };
    Config {
        method: Method::Paper,
        geometry,
        material: Material {
            mu: 1.0,
            alpha11: 1.0,
            alpha22,
            ..Material::default()
        },
        loads: Loads::default(),
        constraints: Constraints {
            fixed_rings: 1,
            ..Constraints::default()
        },
        dnurbs: DnurbsOptions::default(),
        lattice: LatticeOptions {
            constants: crate::paper::paper_constants(),
            ..LatticeOptions::default()
        },
        initial: InitialConditions::default(),
        time: TimeSettings {
            dt: 0.01,
            t_end: 0.1,
            dnurbs_integrator: IntegratorKind::Newmark,
            msm_integrator: IntegratorKind::SymplecticEuler,
        },
        fit: FitOptions::default(),
        probes: vec![(0.5, 0.5)],
        given: None,
        node_damping: None,
    }
}
