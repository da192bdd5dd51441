//! The sweep directory as a signac project: signac (and row, which reads
//! the same layout) finds a job in `workspace/<id>/` by its statepoint
//! `signac_statepoint.json`, and checks that `<id>` is signac's `calc_id`
//! of it: the MD5 of the statepoint as Python's `json.dumps(sp,
//! sort_keys=True)` writes it. [`calc_id`] writes that text exactly
//! (Python's float repr and string escapes), so a point's id is its signac
//! job id; `.signac/config` marks the project (schema 2, signac 2.x) and
//! `signac_job_document.json` (`job.doc`) holds the point's result.

use md5::{Digest, Md5};
use serde_json::Value;

/// The project marker signac 2.x looks for, relative to the sweep root.
pub const CONFIG: &str = ".signac/config";
/// Its contents.
pub const CONFIG_TEXT: &str = "schema_version = 2\n";
/// A job's document (`job.doc`): the point's result, written by irtp.
pub const DOCUMENT: &str = "signac_job_document.json";

/// signac's job id of `statepoint`: the hexadecimal MD5 of
/// [`python_json`].
pub fn calc_id(statepoint: &Value) -> String {
    Md5::digest(python_json(statepoint).as_bytes())
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// `json.dumps(v, sort_keys=True)` of Python 3: separators `, ` and `: `,
/// keys sorted, strings ASCII-only with Python's escapes, floats as
/// Python's `repr`.
pub fn python_json(v: &Value) -> String {
    match v {
        Value::Null => "null".into(),
        Value::Bool(b) => b.to_string(),
        Value::Number(n) => match (n.as_i64(), n.as_u64(), n.as_f64()) {
            (Some(i), _, _) => i.to_string(),
            (None, Some(u), _) => u.to_string(),
            (None, None, Some(x)) => python_float(x),
            _ => n.to_string(),
        },
        Value::String(s) => python_string(s),
        Value::Array(items) => {
            let parts: Vec<String> = items.iter().map(python_json).collect();
            format!("[{}]", parts.join(", "))
        }
        Value::Object(map) => {
            let mut keys: Vec<&String> = map.keys().collect();
            keys.sort();
            let parts: Vec<String> = keys
                .iter()
                .map(|k| format!("{}: {}", python_string(k), python_json(&map[*k])))
                .collect();
            format!("{{{}}}", parts.join(", "))
        }
    }
}

/// Python's `repr` of a finite float: the shortest digits that round-trip
/// (Rust's `{:e}` gives the same digits), fixed notation for decimal
/// exponents -4 ..= 15 with at least one digit after the point, else
/// `d.ddde±XX` (two exponent digits at least).
fn python_float(x: f64) -> String {
    if x == 0.0 {
        return if x.is_sign_negative() { "-0.0" } else { "0.0" }.into();
    }
    let sci = format!("{x:e}");
    let (mantissa, exp) = sci.split_once('e').expect("{:e} has an exponent");
    let exp: i32 = exp.parse().expect("an integer exponent");
    let sign = if mantissa.starts_with('-') { "-" } else { "" };
    let digits: String = mantissa.chars().filter(char::is_ascii_digit).collect();
    let body = if (-4..16).contains(&exp) {
        if exp >= 0 {
            let int_len = exp as usize + 1;
            if digits.len() <= int_len {
                format!("{digits}{}.0", "0".repeat(int_len - digits.len()))
            } else {
                format!("{}.{}", &digits[..int_len], &digits[int_len..])
            }
        } else {
            format!("0.{}{digits}", "0".repeat((-exp - 1) as usize))
        }
    } else {
        let m = if digits.len() == 1 {
            digits.clone()
        } else {
            format!("{}.{}", &digits[..1], &digits[1..])
        };
        let s = if exp < 0 { '-' } else { '+' };
        format!("{m}e{s}{:02}", exp.abs())
    };
    format!("{sign}{body}")
}

/// A JSON string as Python writes it with `ensure_ascii=True`.
fn python_string(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            '\u{8}' => out.push_str("\\b"),
            '\u{c}' => out.push_str("\\f"),
            c if (' '..='~').contains(&c) => out.push(c),
            c => {
                let mut units = [0u16; 2];
                for u in c.encode_utf16(&mut units) {
                    out.push_str(&format!("\\u{u:04x}"));
                }
            }
        }
    }
    out.push('"');
    out
}
