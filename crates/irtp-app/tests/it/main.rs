//! The one integration-test binary of the app layer (commands as library calls, keywords, sweeps).
//! Each module is one former test file; shared helpers live in `common`.

mod app;
mod range_fuzz;
mod search;
