//! `nurbspring`: derive mass-spring models that behave like Dynamic NURBS surfaces.
//! See the library half of this crate for the commands.

fn main() -> std::process::ExitCode {
    nurbspring::main_with_args()
}
