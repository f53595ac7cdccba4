//! Nothing: the benchmarks are `step.rs` (`cargo bench --bench step`); a package needs a target.
