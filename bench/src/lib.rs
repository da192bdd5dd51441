//! The criterion benchmarks of irtp live in `benches/` (run them with
//! `cargo bench -p irtp-bench`, one with `--bench NAME`); this library is
//! empty. See `bench/README.md` for what each measures and how results are
//! compared side by side.
