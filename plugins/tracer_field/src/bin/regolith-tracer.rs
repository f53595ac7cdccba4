//! The `regolith` command line with the `Tracer` field added: what a user's plugin crate
//! ships so its scenes can be run and checked.

fn main() -> std::process::ExitCode {
    regolith_cli::main_with(regolith::Regolith::default().add_plugin(tracer_field::TracerPlugin))
}
