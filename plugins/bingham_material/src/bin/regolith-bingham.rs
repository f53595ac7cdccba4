//! The `regolith` command line with the `Bingham` material added, so that the plugin's
//! scenes can be run, swept and resumed like the shipped ones.

fn main() -> std::process::ExitCode {
    regolith_cli::main_with(
        regolith::Regolith::default().add_plugin(bingham_material::BinghamPlugin),
    )
}
