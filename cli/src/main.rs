//! The `regolith` command with the built-in plugins (see `regolith::cli`).

fn main() -> std::process::ExitCode {
    regolith::cli::main_with(regolith::Regolith::default())
}
