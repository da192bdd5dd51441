//! The `key=value` items of a spec's arguments (`n=0.5,k=1` of
//! `power:n=0.5,k=1`): one parser for every spec of the model (drag, noise,
//! reset target, reset clock, refractory period). An empty item, an item
//! without `=`, an unknown key and a repeated key are refused; each caller
//! wraps the reason into its own error naming its flag and its syntax.

/// The comma-separated items of `text` outside brackets (`[1,2]` is one).
pub fn split_top(text: &str) -> Vec<&str> {
    let (mut depth, mut start, mut out) = (0i32, 0, Vec::new());
    for (i, c) in text.char_indices() {
        match c {
            '[' => depth += 1,
            ']' => depth -= 1,
            ',' if depth == 0 => {
                out.push(&text[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    out.push(&text[start..]);
    out
}

/// The values of `keys` in `args` (None for a key not given), each trimmed:
/// every item `key=value`, each key known and at most once; no arguments
/// at all (`args` blank) give no values. The error is what is wrong, in
/// words.
pub fn pairs<'a>(args: &'a str, keys: &[&str]) -> Result<Vec<Option<&'a str>>, String> {
    let mut values = vec![None; keys.len()];
    if args.trim().is_empty() {
        return Ok(values);
    }
    for item in split_top(args) {
        if item.trim().is_empty() {
            return Err("no empty item (two commas, or one at an end)".into());
        }
        let (key, value) = item
            .split_once('=')
            .ok_or_else(|| format!("key=value pairs, not '{}'", item.trim()))?;
        let key = key.trim();
        let i = keys
            .iter()
            .position(|k| *k == key)
            .ok_or_else(|| format!("the keys {} (unknown key '{key}')", keys.join(", ")))?;
        if values[i].is_some() {
            return Err(format!("each key once ('{key}' repeated)"));
        }
        values[i] = Some(value.trim());
    }
    Ok(values)
}

/// The `allowed` text of a bad spec of `flag`: `what` is wrong, and the
/// syntax (`usage`) where the one-line message stays under 200 characters
/// with the spec echoed; else a pointer to `--help` of the flag.
pub fn reason(flag: &str, spec: &str, what: &str, usage: &str) -> String {
    let full = format!("{what}, in {usage}");
    // "irtp: error: invalid --flag = SPEC: allowed " around it, and a margin.
    let around = 40 + flag.len() + crate::error::echo(spec).chars().count();
    if around + full.chars().count() < 200 {
        full
    } else {
        format!("{what} (syntax: --help of {flag})")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_empty_unknown_and_repeated_items() {
        let keys = ["n", "k"];
        assert_eq!(pairs("n=0.5, k=1", &keys), Ok(vec![Some("0.5"), Some("1")]));
        assert_eq!(pairs(" ", &keys), Ok(vec![None, None]));
        assert_eq!(pairs("k=[1,2]", &keys), Ok(vec![None, Some("[1,2]")]));
        for bad in ["n=0.5,,k=1", "n=0.5,", ",n=0.5", "n=1,n=2", "m=1", "n"] {
            assert!(pairs(bad, &keys).is_err(), "{bad}");
        }
        assert!(pairs("n=1,n=2", &keys)
            .unwrap_err()
            .contains("'n' repeated"));
        assert!(pairs("n=0.5,,k=1", &keys)
            .unwrap_err()
            .contains("empty item"));
    }
}
