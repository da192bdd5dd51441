//! Integration tests of irtp-paper: one binary (`cargo test -p irtp-paper --test it`).
//! The modules beside `gallery` hold the tests of one source file each (the
//! library has no unit tests, so it is compiled once for `cargo test`).

mod fig2;
mod gallery;
mod noise;
mod plot;
mod quicklook;
mod root;
