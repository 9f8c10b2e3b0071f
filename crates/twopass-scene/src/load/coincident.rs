//! Coincident copies of a triangle across the whole scene: found with one hash look-up per
//! triangle, so a scene of many copies (a repeated `f` line, the same mesh placed twice at one
//! place, thousands of `o` groups of one face) loads in linear time.
//!
//! A copy adds no surface: a ray keeps one of the coincident triangles, but the radiosity pass
//! would count each as a surface of its own (an emitter's power multiplied, form factors
//! between coincident surfaces, clusters and shadow rays crossing thousands of them).

use std::collections::HashMap;
use std::path::PathBuf;

use glam::Vec3;

use crate::error::Warning;

/// A triangle's identity: its world corners bit for bit, rotated to start at the smallest, so
/// the same corners in the same cyclic order (the same winding) give the same key. The other
/// winding is another surface (the back of a two-sided wall) and keeps its own key.
pub(super) type CornerKey = [[u32; 3]; 3];

/// The key of the triangle with corners `p`.
pub(super) fn corner_key(p: [Vec3; 3]) -> CornerKey {
    let corners = p.map(|q| q.to_array().map(f32::to_bits));
    let r = (0..3).min_by_key(|&k| corners[k]).unwrap_or(0);
    [corners[r], corners[(r + 1) % 3], corners[(r + 2) % 3]]
}

/// Where a triangle is: its object's name, that object's line (when it has one) and its index
/// within the object.
type Place = (String, Option<usize>, usize);

/// What a triangle is, seen against every triangle kept so far.
pub(super) enum Seen {
    /// No triangle before it has its corners: it is kept.
    New,
    /// A copy of this triangle (index within the object) of the same object.
    InObject(usize),
    /// A copy of a triangle of an earlier object.
    Earlier,
}

/// The triangles kept so far, over the whole scene, and the copies of earlier objects'.
#[derive(Default)]
pub(super) struct Coincident {
    /// Per key: the part (index in load order) and the triangle's index within it.
    kept: HashMap<CornerKey, (usize, usize)>,
    /// Each part's name and line, in load order.
    parts: Vec<(String, Option<usize>)>,
    dropped: usize,
    objects: usize,
    removed: usize,
    first: Option<(Place, Place)>,
    /// Whether the current part has had a copy of an earlier object's triangle.
    in_part: bool,
}

impl Coincident {
    /// Starts the next part (object) in load order.
    pub(super) fn begin(&mut self, name: &str, line: Option<usize>) {
        self.parts.push((name.to_owned(), line));
        self.in_part = false;
    }

    /// Looks up triangle `index` of the current part, with key `key`, and keeps it if new.
    pub(super) fn see(&mut self, key: CornerKey, index: usize) -> Seen {
        let part = self.parts.len() - 1;
        match self.kept.get(&key) {
            None => {
                self.kept.insert(key, (part, index));
                Seen::New
            }
            Some(&(p, original)) if p == part => Seen::InObject(original),
            Some(&(p, original)) => {
                self.dropped += 1;
                if !self.in_part {
                    self.in_part = true;
                    self.objects += 1;
                }
                if self.first.is_none() {
                    let (name, line) = self.parts[part].clone();
                    let (other, other_line) = self.parts[p].clone();
                    self.first = Some(((name, line, index), (other, other_line, original)));
                }
                Seen::Earlier
            }
        }
    }

    /// Whether the current part had copies of an earlier object's triangles.
    pub(super) fn part_had_copies(&self) -> bool {
        self.in_part
    }

    /// Counts the current part, a placed copy of an instanced mesh with `triangles`
    /// triangles, as removed: part `original` already placed the same mesh in the same place.
    pub(super) fn whole_copy(&mut self, original: usize, triangles: usize) {
        let part = self.parts.len() - 1;
        self.dropped += triangles;
        self.objects += 1;
        self.removed += 1;
        if self.first.is_none() {
            let (name, line) = self.parts[part].clone();
            let (other, other_line) = self.parts[original].clone();
            self.first = Some(((name, line, 0), (other, other_line, 0)));
        }
    }

    /// Counts the current part as removed: every triangle it kept was a copy.
    pub(super) fn remove_part(&mut self) {
        self.removed += 1;
    }

    /// The scene's one warning, when any copy was dropped.
    pub(super) fn warning(self, path: PathBuf) -> Option<Warning> {
        let (copy, original) = self.first?;
        Some(Warning::CoincidentObjects {
            path,
            dropped: self.dropped,
            objects: self.objects,
            removed: self.removed,
            copy,
            original,
        })
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use crate::error::Warning;

    /// A floor quad and a light, with the floor placed `copies` more times as objects of
    /// their own (the TOML form of the reproducer: several `[[object]]`s of one mesh).
    fn floor_scene(copies: usize, light_copy: bool) -> String {
        let floor = "shape = { type = \"polygon\", vertices = [[0, 0, 0], [1, 0, 0], [1, 0, -1], [0, 0, -1]] }\n";
        let mut s = String::from(
            "version = 1\n[camera]\nposition = [0.5, 0.5, 2]\nlook_at = [0.5, 0, -0.5]\n\
             [[material]]\nname = \"white\"\ntype = \"lambert\"\ndiffuse = [0.5, 0.5, 0.5]\n",
        );
        let light = "[[object]]\nname = \"light\"\nmaterial = \"white\"\nemission = [1, 1, 1]\n\
                     shape = { type = \"polygon\", vertices = [[0, 1, 0], [0, 1, -1], [1, 1, -1], [1, 1, 0]] }\n";
        s.push_str(light);
        for i in 0..=copies {
            s.push_str(&format!(
                "[[object]]\nname = \"floor{i}\"\nmaterial = \"white\"\n{floor}"
            ));
        }
        if light_copy {
            s.push_str(&light.replace("\"light\"", "\"light2\""));
        }
        s
    }

    #[test]
    fn copies_of_earlier_objects_are_dropped_and_empty_objects_removed() {
        let text = floor_scene(3, true);
        let (scene, warnings) = crate::load_toml(&text, Path::new("floors.toml")).unwrap();
        // The light and one floor: two triangles each.
        assert_eq!(scene.mesh.triangles.len(), 4);
        let names: Vec<&str> = scene.objects.iter().map(|o| o.name.as_str()).collect();
        assert_eq!(names, ["light", "floor0"]);
        // The removed objects' vertices go with them: the two quads' corners are left.
        assert_eq!(scene.mesh.positions.len(), 8);
        // The light's copy would have doubled its power: one emitter of the quad's area.
        assert_eq!(scene.emitters.len(), 1);
        assert!((scene.emitters[0].area - 1.0).abs() < 1e-6);
        let w: Vec<&Warning> = warnings
            .iter()
            .filter(|w| matches!(w, Warning::CoincidentObjects { .. }))
            .collect();
        assert_eq!(w.len(), 1, "{warnings:?}");
        // Lines: the light's `[[object]]` is on line 9, each floor's 4 lines later.
        assert_eq!(
            w[0].to_string(),
            "floors.toml: dropped 8 triangle(s) in 4 object(s) that repeat a triangle of an \
             earlier object exactly (same corners, same winding); 4 object(s) left with no \
             triangle were removed; the first is triangle 0 of object `floor1` (line 18), a \
             copy of triangle 0 of object `floor0` (line 14)"
        );
    }

    #[test]
    fn the_other_winding_is_another_surface() {
        // The floor's back face (its corners in the other order) as an object of its own.
        let text = floor_scene(0, false)
            + "[[object]]\nname = \"under\"\nmaterial = \"white\"\n\
               shape = { type = \"polygon\", vertices = [[0, 0, -1], [1, 0, -1], [1, 0, 0], [0, 0, 0]] }\n";
        let (scene, warnings) = crate::load_toml(&text, Path::new("floors.toml")).unwrap();
        assert_eq!(scene.objects.len(), 3);
        assert!(
            !warnings
                .iter()
                .any(|w| matches!(w, Warning::CoincidentObjects { .. })),
            "{warnings:?}"
        );
    }

    /// 10^5 objects, each one copy of the floor: loaded in linear time (one hash look-up per
    /// triangle) into one floor, with one warning.
    #[test]
    fn a_hundred_thousand_copies_as_objects_load_as_one() {
        let text = floor_scene(100_000, false);
        let (scene, warnings) = crate::load_toml(&text, Path::new("floors.toml")).unwrap();
        assert_eq!(scene.objects.len(), 2);
        assert_eq!(scene.mesh.triangles.len(), 4);
        assert!(
            warnings.iter().any(|w| w
                .to_string()
                .contains("dropped 200000 triangle(s) in 100000 object(s)")),
            "{warnings:?}"
        );
    }
}
