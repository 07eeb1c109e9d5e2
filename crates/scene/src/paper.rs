//! The paper's experiment (Section IV) on its built-in scene: the paper's derivation, every
//! reading of it ([`nurbspring_derive::paper`]), and the default (modal) derivation beside it.

use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use nurbspring_derive::paper::{PaperReport, readings, reproduce_cancellable};
use nurbspring_derive::{Derivation, Method};

use crate::markdown::verdict_table;
use crate::report::{how_run, write_derived_files_with, write_reports};
use crate::{Error, Scene};

/// How the built-in scene is named in the reports.
pub const PAPER_LABEL: &str = "built-in paper scene (examples/paper.toml)";

impl Scene {
    /// The paper's derivation of this scene and every reading of it; `cancel` stops it
    /// between steps, `progress(done, total)` follows the mass scan.
    pub fn reproduce_paper(
        &self,
        cancel: Option<Arc<AtomicBool>>,
        progress: &mut dyn FnMut(usize, usize),
    ) -> Result<(Derivation, PaperReport), Error> {
        let config = self.derivation_config(Some(Method::Paper))?;
        reproduce_cancellable(&config, cancel, progress)
            .map_err(|e| Error::model(&self.path, None, e))
    }

    /// The paper's experiment written into `out` (every file of a derivation, the MSM of the
    /// default derivation beside the paper's in the central node's figure, report.json and
    /// report.md); returns the verdict table. `progress` follows the paper's mass scan,
    /// `derived` is called when the paper's derivation is done.
    pub fn write_paper_experiment(
        &self,
        out: &Path,
        cancel: Option<Arc<AtomicBool>>,
        progress: &mut dyn FnMut(usize, usize),
        derived: &mut dyn FnMut(),
    ) -> Result<String, Error> {
        let config = self.derivation_config(Some(Method::Paper))?;
        let model_error = |e| Error::model(&self.path, None, e);
        let (main, main_setup) =
            nurbspring_derive::derive(&config, cancel.clone(), progress).map_err(model_error)?;
        derived();
        // The default derivation of the same scene, whose MSM the central node's figure shows
        // beside the paper's: what this project adds.
        let modal_config = self.derivation_config(Some(Method::Modal))?;
        let (modal, _) = nurbspring_derive::derive(&modal_config, cancel.clone(), &mut |_, _| {})
            .map_err(model_error)?;
        let modal_curve = (
            format!(
                "MSM of the default (modal) derivation: {}",
                how_run(&modal.derived)
            ),
            &modal.msm_trajectory,
        );
        // The main derivation's files (plots among them) are written while the readings run.
        let (report, written) = rayon::join(
            || readings(&config, &main, &main_setup, cancel.clone()),
            || {
                write_derived_files_with(
                    out,
                    PAPER_LABEL,
                    self,
                    &main,
                    std::slice::from_ref(&modal_curve),
                )
            },
        );
        written?;
        let report = report.map_err(model_error)?;
        let table = verdict_table(&report);
        write_reports(out, PAPER_LABEL, self, &main, Some(&report), &table)?;
        Ok(table)
    }
}
