//! Integration tests of irtp-paper: one binary (`cargo test -p irtp-paper --test it`).

mod gallery;
