//! Running a D-NURBS model: every integrator of `nurbspring-sim` for constant weights, the
//! weights-as-unknowns scheme of [`RationalStepper`] otherwise (docs/math.md §3), behind one
//! call with one observer.

use std::sync::atomic::Ordering;

use nurbspring_sim::{
    DynamicModel, IntegratorKind, Observer, RunOptions, RunSummary, Sample, State, simulate,
};

use crate::{Assembler, DnurbsError, DnurbsModel, DnurbsOptions, MaterialModel, RationalStepper};

/// Why `integrator` cannot run a D-NURBS with this material and these options; `None` when it
/// can. The one place these rules live: [`DnurbsModel::simulate`] and the scene checks use it.
pub fn integrator_problem(
    integrator: IntegratorKind,
    material: &MaterialModel,
    options: &DnurbsOptions,
) -> Option<String> {
    let material = match material {
        MaterialModel::TensionPlate(m) => m,
        MaterialModel::KirchhoffLove(_) => {
            return (!DnurbsModel::SHELL_INTEGRATORS.contains(&integrator)).then(|| {
                format!(
                    "the Kirchhoff–Love shell is nonlinear: {} (linear models only) cannot run it; \
                     expected one of {}",
                    integrator.name(),
                    names(&DnurbsModel::SHELL_INTEGRATORS)
                )
            });
        }
    };
    if !DnurbsModel::INTEGRATORS.contains(&integrator) {
        return Some(format!(
            "not an integrator of the D-NURBS model; expected one of {}",
            names(&DnurbsModel::INTEGRATORS)
        ));
    }
    if options.weights_as_dofs && integrator != IntegratorKind::TerzopoulosQin {
        return Some(format!(
            "with weights as unknowns (dnurbs.weights_as_dofs = true) M, D and K change with the \
             shape and the one scheme is the weights-as-unknowns Terzopoulos–Qin step; expected \
             {}",
            IntegratorKind::TerzopoulosQin.name()
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
    /// The integrators a Kirchhoff–Love shell runs with: implicit with Newton on the
    /// consistent tangent at every step, or central differences (velocity Verlet) with the
    /// consistent mass factored once, below the stability limit of the rest state.
    pub const SHELL_INTEGRATORS: [IntegratorKind; 4] = [
        IntegratorKind::Newmark,
        IntegratorKind::GeneralizedAlpha,
        IntegratorKind::BackwardEuler,
        IntegratorKind::VelocityVerlet,
    ];

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
    /// weights-as-unknowns Terzopoulos–Qin step of [`RationalStepper`] (any other integrator is
    /// refused by [`integrator_problem`]); its samples carry the energies of the current shape,
    /// `½ ṗᵀ M(p) ṗ` and `½ (p − p_rest)ᵀ K(p) (p − p_rest)`, with M and K assembled at the
    /// sample's own `p` and the velocity at the sample's own time (docs/math.md §3), and the
    /// load potential `−qᵀ f` of the load `f` assembled on the initial shape.
    /// The run stops after the current step when `opts.cancel` is set.
    pub fn simulate(
        &self,
        initial: State,
        opts: &RunOptions,
        observer: &mut dyn Observer,
    ) -> Result<RunSummary, DnurbsError> {
        if let Some(reason) =
            integrator_problem(opts.integrator, &self.material_model(), &self.options)
        {
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
        let assembler = Assembler::new(&self.geometry, &self.options)?;
        let energy = |q: &[f64], v: &[f64]| self.energies_with(&assembler, q, v);
        let (kinetic, elastic) = energy(&initial.q, &initial.v)?;
        let external = self.external_potential(initial.t, &initial.q);
        observer.observe(&Sample {
            step: 0,
            t: initial.t,
            q: &initial.q,
            v: &initial.v,
            kinetic,
            potential: elastic + external,
            elastic,
            external,
        });
        let mut summary = RunSummary {
            steps: 0,
            t_final: initial.t,
            cancelled: false,
            omega_max: None,
            dt_critical: None,
            halved_steps: 0,
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
            let (kinetic, elastic) = energy(&s.q, &s.v)?;
            let external = self.external_potential(s.t, &s.q);
            summary.steps += 1;
            summary.t_final = s.t;
            observer.observe(&Sample {
                step: summary.steps,
                t: s.t,
                q: &s.q,
                v: &s.v,
                kinetic,
                potential: elastic + external,
                elastic,
                external,
            });
        }
        Ok(summary)
    }
}

impl DnurbsModel {
    /// The kinetic energy `½ ṗᵀ M(p) ṗ` and the elastic energy `½ (p − p_rest)ᵀ K(p) (p − p_rest)`
    /// of the reduced state `(q, v)`, with M and K of the shape `p = P q + o` itself
    /// (docs/math.md §3). With constant weights M and K are those of the model.
    pub fn energies(&self, q: &[f64], v: &[f64]) -> Result<(f64, f64), DnurbsError> {
        if !self.options.weights_as_dofs {
            let vf = self.full_velocity(v);
            return Ok((
                0.5 * self.matrices.mass.quadratic_form(&vf),
                self.elastic_energy(&self.full_coordinates(q)),
            ));
        }
        self.energies_with(&Assembler::new(&self.geometry, &self.options)?, q, v)
    }

    fn energies_with(
        &self,
        assembler: &Assembler,
        q: &[f64],
        v: &[f64],
    ) -> Result<(f64, f64), DnurbsError> {
        let p = self.full_coordinates(q);
        let vf = self.full_velocity(v);
        let geometry = self
            .geometry
            .with_coordinates(&p, self.options.weights_as_dofs)?;
        let m = assembler.assemble(&geometry, &self.material, &self.loads)?;
        let d: Vec<f64> = p.iter().zip(&self.p_rest).map(|(a, b)| a - b).collect();
        Ok((
            0.5 * m.mass.quadratic_form(&vf),
            0.5 * m.stiffness.quadratic_form(&d),
        ))
    }
}
