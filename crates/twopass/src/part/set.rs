//! A set of part files read and checked as one job: every file whole, of one kind, scene,
//! split and settings, each part exactly once. Nothing is merged from a mixed set; the first
//! problem found is the error, naming the file and what is wrong.

use std::path::{Path, PathBuf};

use super::file::{Cost, PartHeader, Payload, read};
use crate::error::CliError;

/// One part file of a set.
pub struct Part {
    /// The file.
    pub path: PathBuf,
    /// Its header.
    pub header: PartHeader,
    /// Its values.
    pub payload: Payload,
}

/// A checked, complete set of parts, ordered by part index.
pub struct PartSet {
    /// The header of part 1 (every part's job is the same).
    pub header: PartHeader,
    /// Every part, part 1 first.
    pub parts: Vec<Part>,
    /// The parts' costs summed.
    pub cost: Cost,
}

/// Reads `paths` and checks them as one set (see the module docs).
pub fn read_set(paths: &[PathBuf]) -> Result<PartSet, CliError> {
    let mut parts = Vec::with_capacity(paths.len());
    for path in paths {
        let (header, payload) = read(path)?;
        parts.push(Part {
            path: path.clone(),
            header,
            payload,
        });
    }
    let Some(first) = parts.first() else {
        return Err(CliError::Usage("merge: no part files given".into()));
    };
    let (f, fp) = (&first.header, &first.path);
    for p in &parts[1..] {
        let (h, name) = (&p.header, p.path.display());
        if h.kind != f.kind {
            return Err(mixed(format!(
                "{name}: a {} part, but {} is a {} part",
                h.kind,
                fp.display(),
                f.kind
            )));
        }
        if h.scene_fingerprint != f.scene_fingerprint {
            return Err(mixed(format!(
                "{name}: a part of another scene ({} with fingerprint {}; {} is of {} with \
                 fingerprint {})",
                h.scene.display(),
                h.scene_fingerprint,
                fp.display(),
                f.scene.display(),
                f.scene_fingerprint
            )));
        }
        if h.part.of != f.part.of {
            return Err(mixed(format!(
                "{name}: part {} of another split ({} is part {})",
                h.part,
                fp.display(),
                f.part
            )));
        }
        if let Some(why) = differing_setting(&h.settings, &f.settings) {
            return Err(mixed(format!("{name}: {why} as in {}", fp.display())));
        }
    }
    parts.sort_by_key(|p| p.header.part.index);
    for pair in parts.windows(2) {
        if pair[0].header.part.index == pair[1].header.part.index {
            return Err(mixed(format!(
                "{}: part {} again ({} is part {} too)",
                pair[1].path.display(),
                pair[1].header.part,
                pair[0].path.display(),
                pair[0].header.part
            )));
        }
    }
    let of = parts[0].header.part.of;
    let missing: Vec<String> = (1..=of)
        .filter(|i| {
            parts
                .binary_search_by_key(i, |p| p.header.part.index)
                .is_err()
        })
        .map(|i| format!("{i}/{of}"))
        .collect();
    if !missing.is_empty() {
        let given = parts
            .iter()
            .map(|p| format!("{} ({})", p.header.part, file_name(&p.path)))
            .collect::<Vec<_>>()
            .join(", ");
        let (s, verb) = if missing.len() == 1 {
            ("", "is")
        } else {
            ("s", "are")
        };
        return Err(mixed(format!(
            "part{s} {} {verb} missing; given: {given}",
            missing.join(", ")
        )));
    }
    let cost = parts.iter().fold(Cost::default(), |c, p| Cost {
        rays: c.rays + p.header.cost.rays,
        shadow_rays: c.shadow_rays + p.header.cost.shadow_rays,
        seconds: c.seconds + p.header.cost.seconds,
    });
    Ok(PartSet {
        header: parts[0].header.clone(),
        parts,
        cost,
    })
}

/// A set that cannot be merged: the problem, and that nothing was written.
fn mixed(why: String) -> CliError {
    CliError::Input(format!("{why}; nothing merged"))
}

fn file_name(p: &Path) -> String {
    p.file_name().map_or_else(
        || p.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

/// The first setting whose value differs between `a` and `b` (in `b`'s key order, then keys
/// only `a` has), said as "another seed: 2, not 1".
fn differing_setting(
    a: &serde_json::Map<String, serde_json::Value>,
    b: &serde_json::Map<String, serde_json::Value>,
) -> Option<String> {
    let null = serde_json::Value::Null;
    b.keys()
        .chain(a.keys().filter(|k| !b.contains_key(*k)))
        .find(|k| a.get(*k).unwrap_or(&null) != b.get(*k).unwrap_or(&null))
        .map(|k| {
            format!(
                "another {k}: {}, not {}",
                a.get(k).unwrap_or(&null),
                b.get(k).unwrap_or(&null)
            )
        })
}
