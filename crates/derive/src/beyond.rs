//! "Beyond the paper" (docs/math.md §8): the default derivation on the paper's own scene,
//! side by side with the paper's, both judged against the exact D-NURBS motion over the
//! paper's 4 s and over 40 s.

use nurbspring_msm::{Class, FixedNodes, LinearKind};
use serde::Serialize;

use crate::DeriveError;
use crate::dispatch::derive;
use crate::method::Method;
use crate::outcome::Derivation;
use crate::setup::Config;
use crate::validation::compare_points;

/// The horizons compared [s].
pub const HORIZONS: [f64; 2] = [4.0, 40.0];

/// One derivation on the paper's scene.
#[derive(Clone, Debug, Serialize)]
pub struct BeyondRow {
    /// The derivation.
    pub derivation: Method,
    /// Its lattice: grid and nodes.
    pub lattice: String,
    /// Σ m of its free nodes against the D-NURBS's free mass.
    pub free_mass: (f64, f64),
    /// Lowest angular frequency against the D-NURBS's (`None`: the model has none).
    pub omega1: (Option<f64>, f64),
    /// Relative RMS of the central node (3-D, against the exact D-NURBS) over each horizon.
    pub relative_rms: Vec<(f64, f64)>,
}

/// The default derivation beside the paper's on the paper's scene.
#[derive(Clone, Debug, Serialize)]
pub struct Beyond {
    /// One row per derivation, the paper's first.
    pub rows: Vec<BeyondRow>,
}

fn windows(d: &Derivation) -> Vec<(f64, f64)> {
    let t = &d.dnurbs_trajectory.t;
    HORIZONS
        .iter()
        .map(|&h| {
            let n = t.iter().take_while(|&&x| x <= h + 1e-9).count();
            let c = compare_points(
                &t[..n],
                &d.dnurbs_trajectory.probes[0][..n.min(d.dnurbs_trajectory.probes[0].len())],
                &d.msm_trajectory.probes[0][..n.min(d.msm_trajectory.probes[0].len())],
            );
            (
                h,
                if d.msm_trajectory.stopped.is_some() {
                    f64::INFINITY
                } else {
                    c.relative_rms
                },
            )
        })
        .collect()
}

fn row(d: &Derivation) -> BeyondRow {
    let lattice = d
        .lattice()
        .map(|l| {
            let (u, v) = l.grid.unwrap_or((l.n_nodes(), 1));
            format!(
                "{u} x {v} nodes, {} free",
                l.fixed.iter().filter(|f| !**f).count()
            )
        })
        .unwrap_or_default();
    BeyondRow {
        derivation: d.method(),
        lattice,
        free_mass: (d.mass.free_msm, d.mass.free_dnurbs),
        omega1: (
            d.frequencies.first().map(|f| f.msm),
            d.frequencies.first().map(|f| f.dnurbs).unwrap_or(f64::NAN),
        ),
        relative_rms: windows(d),
    }
}

/// The default derivation (modal, on the Greville lattice with every linear element class)
/// on the paper's scene `base`, beside `paper`, the paper's derivation of the same scene.
pub fn beyond(base: &Config, paper: &Derivation) -> Result<Beyond, DeriveError> {
    let mut config = base.clone();
    config.method = Method::Modal;
    config.lattice.grid = Method::Modal.default_grid();
    config.lattice.fixed = FixedNodes::Auto;
    config.lattice.constants = nurbspring_msm::Constants::from_pairs(
        Class::linear(&LinearKind::ALL)
            .into_iter()
            .map(|c| (c, 1.0)),
    );
    config.given = None;
    let (modal, _) = derive(&config, None, &mut |_, _| {})?;
    Ok(Beyond {
        rows: vec![row(paper), row(&modal)],
    })
}
