//! The `regolith` command: the built-in plugins and, with the default `rerun` feature, the
//! Rerun recorder (see [`regolith_cli::main_with`]).

fn main() -> std::process::ExitCode {
    let app = regolith::Regolith::default();
    #[cfg(feature = "rerun")]
    let app = app.add_plugin(regolith_rerun::RerunPlugin);
    regolith_cli::main_with(app)
}
