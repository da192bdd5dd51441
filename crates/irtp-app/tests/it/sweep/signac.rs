//! The sweep as a signac project (`irtp_app::sweep::signac`): the texts and
//! ids Python writes.

use irtp_app::sweep::signac::{calc_id, python_json};

/// The texts Python 3 prints for these values (`json.dumps`, `repr`):
/// floats and strings as `python_json` writes them.
#[test]
fn floats_and_strings_as_python_writes_them() {
    for (x, py) in [
        (1.0, "1.0"),
        (0.1, "0.1"),
        (-2.5, "-2.5"),
        (1e-5, "1e-05"),
        (0.0001, "0.0001"),
        (1e16, "1e+16"),
        (1e15, "1000000000000000.0"),
        (1.5e-7, "1.5e-07"),
        (123456.789, "123456.789"),
        (1.6938775510204083, "1.6938775510204083"),
        (5e-324, "5e-324"),
        (1.7976931348623157e308, "1.7976931348623157e+308"),
        (-0.0, "-0.0"),
    ] {
        assert_eq!(python_json(&serde_json::json!(x)), py, "{x:e}");
    }
    assert_eq!(
        python_json(&serde_json::json!("a\"b\\c\nü€😀")),
        r#""a\"b\\c\n\u00fc\u20ac\ud83d\ude00""#
    );
}

/// `json.dumps({"seed": None, "command": "fp stationary", "parameters":
/// {"sigma": 3.0, "cells": 200, "lambda": 0.5}}, sort_keys=True)` and
/// its MD5, as Python computes them.
#[test]
fn a_statepoint_as_signac_hashes_it() {
    let sp = serde_json::json!({"seed": null, "command": "fp stationary",
        "parameters": {"sigma": 3.0, "cells": 200, "lambda": 0.5}});
    let text = python_json(&sp);
    assert_eq!(
        text,
        r#"{"command": "fp stationary", "parameters": {"cells": 200, "lambda": 0.5, "sigma": 3.0}, "seed": null}"#
    );
    assert_eq!(calc_id(&sp), "745bed56de3a4150b6b564ad9a6f7d93");
}
