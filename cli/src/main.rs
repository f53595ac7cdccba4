//! The `regolith` command: the built-in plugins and the Rerun recorder (see `regolith::cli`).

fn main() -> std::process::ExitCode {
    regolith::cli::main_with(regolith::Regolith::default().add_plugin(regolith_rerun::RerunPlugin))
}
