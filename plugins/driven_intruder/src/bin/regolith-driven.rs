//! The `regolith` command line with the `Driven` condition added.

fn main() -> std::process::ExitCode {
    regolith_cli::main_with(
        regolith::Regolith::default().add_plugin(driven_intruder::DrivenIntruderPlugin),
    )
}
