//! The one integration-test binary of the app layer (commands as library calls, keywords, sweeps).
//! Each module is one former test file, or the tests of one source file
//! (the library has no unit tests, so it is compiled once for `cargo test`);
//! shared helpers live in `common`.

mod app;
mod applies;
mod budget;
mod format;
mod io;
mod lock;
mod range_fuzz;
mod search;
mod sweep;
