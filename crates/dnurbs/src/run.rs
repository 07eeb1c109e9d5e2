//! Running a D-NURBS model: every integrator of `nurbspring-sim` for constant weights, the
//! weights-as-unknowns scheme of [`RationalStepper`] otherwise (docs/math.md §3), behind one
//! call with one observer.

use std::sync::atomic::Ordering;

use nurbspring_sim::{IntegratorKind, Observer, RunOptions, RunSummary, Sample, State, simulate};

use crate::{DnurbsError, DnurbsModel, DnurbsOptions, Material, RationalStepper};

/// Why `integrator` cannot run a D-NURBS with this material and these options; `None` when it
/// can. The one place these rules live: [`DnurbsModel::simulate`] and the scene checks use it.
pub fn integrator_problem(
    integrator: IntegratorKind,
    material: &Material,
    options: &DnurbsOptions,
) -> Option<String> {
    if !DnurbsModel::INTEGRATORS.contains(&integrator) {
        return Some(format!(
            "not an integrator of the D-NURBS model; expected one of {}",
            names(&DnurbsModel::INTEGRATORS)
        ));
    }
    if integrator == IntegratorKind::Modal {
        if material.gamma != 0.0 {
            return Some(format!(
                "the modal solution needs an undamped model, but material.gamma = {}",
                material.gamma
            ));
        }
        if options.weights_as_dofs {
            return Some(
                "the modal solution needs constant weights (dnurbs.weights_as_dofs = false)"
                    .to_string(),
            );
        }
    }
    None
}

/// `a, b, c` of integrator names.
pub fn names(kinds: &[IntegratorKind]) -> String {
    kinds
        .iter()
        .map(|k| k.name())
        .collect::<Vec<_>>()
        .join(", ")
}

impl DnurbsModel {
    /// The integrators a D-NURBS runs with.
    pub const INTEGRATORS: [IntegratorKind; 3] = [
        IntegratorKind::TerzopoulosQin,
        IntegratorKind::Newmark,
        IntegratorKind::Modal,
    ];

    /// Runs the model from `initial` (reduced coordinates) to `opts.t_end`, calling `observer`
    /// at t = 0 and after every step.
    ///
    /// With constant weights this is [`nurbspring_sim::simulate`] with `opts.integrator`. With
    /// weights as unknowns the matrices change with the shape, and the one scheme is the
    /// weights-as-unknowns Terzopoulos–Qin step of [`RationalStepper`] (`opts.integrator` is
    /// not used); its samples carry the kinetic energy `½ ṗᵀ M(p(0)) ṗ` and the elastic
    /// energy `½ (p − p_rest)ᵀ K(p(0)) (p − p_rest)` with the matrices of the initial shape.
    /// The run stops after the current step when `opts.cancel` is set.
    pub fn simulate(
        &self,
        initial: State,
        opts: &RunOptions,
        observer: &mut dyn Observer,
    ) -> Result<RunSummary, DnurbsError> {
        if let Some(reason) = integrator_problem(opts.integrator, &self.material, &self.options) {
            return Err(DnurbsError::InvalidOption {
                name: "integrator",
                value: opts.integrator.name().to_string(),
                reason,
            });
        }
        if !self.options.weights_as_dofs {
            return Ok(simulate(self, initial, opts, observer)?);
        }
        opts.validate(initial.t)?;
        let energy = |q: &[f64], v: &[f64]| {
            let vf = self.full_velocity(v);
            (
                0.5 * self.matrices().mass.quadratic_form(&vf),
                self.elastic_energy(&self.full_coordinates(q)),
            )
        };
        let (kinetic, potential) = energy(&initial.q, &initial.v);
        observer.observe(&Sample {
            step: 0,
            t: initial.t,
            q: &initial.q,
            v: &initial.v,
            kinetic,
            potential,
        });
        let mut summary = RunSummary {
            steps: 0,
            t_final: initial.t,
            cancelled: false,
            omega_max: None,
            dt_critical: None,
        };
        let dt = opts.dt;
        let mut stepper = RationalStepper::new(self, initial, dt)?;
        while stepper.state().t < opts.t_end - 0.5 * dt {
            if opts
                .cancel
                .as_ref()
                .is_some_and(|c| c.load(Ordering::Relaxed))
            {
                summary.cancelled = true;
                break;
            }
            stepper.step()?;
            let s = stepper.state();
            let (kinetic, potential) = energy(&s.q, &s.v);
            summary.steps += 1;
            summary.t_final = s.t;
            observer.observe(&Sample {
                step: summary.steps,
                t: s.t,
                q: &s.q,
                v: &s.v,
                kinetic,
                potential,
            });
        }
        Ok(summary)
    }
}
