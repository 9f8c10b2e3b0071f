//! Index lists and the search for the line an error is on (tobj reports no position).

use glam::Vec3;

/// A triangulated group's flat index list (positions, normals or texture coordinates) as one
/// triple per triangle.
pub(super) fn triples(indices: &[u32]) -> Vec<[u32; 3]> {
    indices
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect()
}

pub(super) fn first_non_finite(v: &[Vec3]) -> Option<(usize, f32)> {
    v.iter().enumerate().find_map(|(i, p)| {
        p.to_array()
            .into_iter()
            .find(|c| !c.is_finite())
            .map(|c| (i, c))
    })
}

/// The 1-based line of the first `keyword` statement holding a non-finite number.
pub(super) fn find_non_finite_line(text: &str, keyword: &str) -> Option<usize> {
    find_value_line(text, keyword, |x| !x.is_finite())
}

/// The 1-based line of the first `keyword` statement holding a number `bad` is true of.
pub(super) fn find_value_line(
    text: &str,
    keyword: &str,
    bad: impl Fn(f32) -> bool,
) -> Option<usize> {
    text.lines().enumerate().find_map(|(i, l)| {
        let mut it = l.split_whitespace();
        (it.next() == Some(keyword) && it.any(|w| w.parse::<f32>().is_ok_and(&bad)))
            .then_some(i + 1)
    })
}

/// The 1-based line tobj most likely failed on: the first statement of the kind its error
/// names that does not parse (tobj reports no position).
pub(super) fn find_bad_line(text: &str, err: tobj::LoadError) -> Option<usize> {
    use tobj::LoadError as E;
    let (mut nv, mut nvt, mut nvn) = (0i64, 0i64, 0i64);
    let index_ok = |s: &str, n: i64| {
        s.parse::<i64>()
            .is_ok_and(|i| (1..=n).contains(&i) || (-n..=-1).contains(&i))
    };
    let floats = |it: std::str::SplitWhitespace, min: usize, max: usize| {
        let v: Vec<&str> = it.collect();
        (min..=max).contains(&v.len()) && v.iter().all(|w| w.parse::<f32>().is_ok())
    };
    for (i, line) in text.lines().enumerate() {
        let mut it = line.split_whitespace();
        let bad = match it.next() {
            Some("v") => {
                nv += 1;
                matches!(err, E::PositionParseError | E::ColorParseError) && !floats(it, 3, 7)
            }
            Some("vt") => {
                nvt += 1;
                matches!(err, E::TexcoordParseError) && !floats(it, 1, 3)
            }
            Some("vn") => {
                nvn += 1;
                matches!(err, E::NormalParseError) && !floats(it, 3, 3)
            }
            Some("f") => {
                let corners: Vec<&str> = it.collect();
                let face_err = matches!(
                    err,
                    E::FaceParseError
                        | E::InvalidPolygon
                        | E::FaceVertexOutOfBounds
                        | E::FaceTexCoordOutOfBounds
                        | E::FaceNormalOutOfBounds
                );
                face_err
                    && (corners.len() < 3
                        || !corners.iter().all(|c| {
                            let parts: Vec<&str> = c.split('/').collect();
                            parts.len() <= 3
                                && index_ok(parts[0], nv)
                                && parts
                                    .get(1)
                                    .is_none_or(|t| t.is_empty() || index_ok(t, nvt))
                                && parts
                                    .get(2)
                                    .is_none_or(|n| n.is_empty() || index_ok(n, nvn))
                        }))
            }
            _ => false,
        };
        if bad {
            return Some(i + 1);
        }
    }
    None
}
