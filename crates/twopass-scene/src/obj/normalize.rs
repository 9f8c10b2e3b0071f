//! Valid OBJ statements tobj reads wrongly, rewritten (one line for one, so lines keep their
//! numbers) into forms it reads right.

use std::borrow::Cow;

/// The text tobj parses: `text` with
/// - `vt u` (one component; v defaults to 0) written `vt u 0` (tobj wants two);
/// - `v x y z r g b` written `v x y z` (the colour is not used, and tobj refuses a file where
///   some vertices have one and others not);
/// - `mtllib` and `usemtl` followed by one space and their trimmed argument (tobj splits
///   them at the first space, so a tab after the keyword loses the name, and leading white
///   space makes the keyword part of it).
///
/// Other lines are kept as they are. Borrowed when nothing changes.
pub(super) fn normalize(text: &str) -> Cow<'_, str> {
    let mut out: Option<String> = None;
    let mut done = 0;
    for (start, line) in line_starts(text) {
        let Some(fixed) = rewrite(line) else {
            continue;
        };
        let o = out.get_or_insert_with(|| String::with_capacity(text.len() + 64));
        o.push_str(&text[done..start]);
        o.push_str(&fixed);
        done = start + line.len();
    }
    match out {
        None => Cow::Borrowed(text),
        Some(mut o) => {
            o.push_str(&text[done..]);
            Cow::Owned(o)
        }
    }
}

/// Each line's byte offset and text, without its line ending (`\n` or `\r\n`), as
/// [`str::lines`] splits them.
fn line_starts(text: &str) -> impl Iterator<Item = (usize, &str)> {
    let mut start = 0;
    text.split_inclusive('\n').map(move |raw| {
        let at = start;
        start += raw.len();
        let line = raw.strip_suffix('\n').unwrap_or(raw);
        (at, line.strip_suffix('\r').unwrap_or(line))
    })
}

/// The rewritten line, or `None` when tobj reads it right as it is.
fn rewrite(line: &str) -> Option<String> {
    let mut words = line.split_whitespace();
    let keyword = words.next()?;
    match keyword {
        "vt" => {
            let values: Vec<&str> = words.collect();
            (values.len() == 1).then(|| format!("vt {} 0", values[0]))
        }
        "v" => {
            let values: Vec<&str> = words.collect();
            (values.len() == 6).then(|| format!("v {} {} {}", values[0], values[1], values[2]))
        }
        "mtllib" | "usemtl" => {
            let rest = line.trim_start()[keyword.len()..].trim();
            let fixed = format!("{keyword} {rest}");
            (fixed != line).then_some(fixed)
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[rustfmt::skip]
    const CASES: &[(&str, &str)] = &[
        ("v 1 2 3\nvt 0.5 0.25\nf 1 2 3\n",       "v 1 2 3\nvt 0.5 0.25\nf 1 2 3\n"),
        ("vt 0.5\n",                              "vt 0.5 0\n"),
        ("v 1 2 3 0.1 0.2 0.3\r\nv 4 5 6\r\n",    "v 1 2 3\r\nv 4 5 6\r\n"),
        ("v 1 2 3 2\n",                           "v 1 2 3 2\n"),
        ("usemtl\twhite\n",                       "usemtl white\n"),
        ("  mtllib  a b.mtl \nf 1 2 3",           "mtllib a b.mtl\nf 1 2 3"),
        ("usemtl white",                          "usemtl white"),
    ];

    #[test]
    fn statements_tobj_misreads_are_rewritten_line_for_line() {
        for (text, want) in CASES {
            let got = normalize(text);
            assert_eq!(got, *want, "{text:?}");
            assert_eq!(got.lines().count(), text.lines().count());
            assert_eq!(matches!(got, Cow::Borrowed(_)), text == want, "{text:?}");
        }
    }
}
