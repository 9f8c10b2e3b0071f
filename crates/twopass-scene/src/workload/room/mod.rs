//! A family of generated test rooms for measuring bakes on scenes nobody tuned for, each
//! unlike the Cornell box and unlike the others (issue 39): deterministic from a seed, written
//! as a scene file (TOML) plus an OBJ of the bulk geometry without normals or texture
//! coordinates (as a user's export would be), the camera inside the room, 256 x 256 by
//! default, in metres, emission set so the mean pixel radiance is of the order of
//! 0.2 to 1 W/(m^2 sr).
//!
//! | room | what it tests |
//! | --- | --- |
//! | `spheres` | 20 x 20 x 8: floating spheres of many sizes (one about 3 across lit at a slant, one big one in front of the camera), boxes on the floor, one 4 x 4 light under the ceiling; grey 0.5; its size in triangles is a setting |
//! | `grazing` | a long low room (6 x 4 x 30) lit by one light on an end wall, so light reaches floor and ceiling at grazing angles; 0.05-thick shelves on the side walls; a sphere and a box on the floor |
//! | `near-light` | small curved objects close to walls and very close under a small bright 1 x 1 light; albedo 0.8 (many bounces) |
//! | `two-lights` | a 0.5 x 0.5 and a 3 x 3 light of different power, a red wall (0.6, 0.2, 0.2), a big sphere on the floor, a thin slab leaning on a wall |
//! | `terminator` | one coarse sphere (icosphere level 2: 320 triangles) on a floor, lit at a slant, seen across its terminator (the sawtooth test) |
//! | `chrome` | 16 x 8 x 16: glass, chrome and diffuse balls and thin chrome rings on a plate under seventeen strip lights, about 100k triangles (caustics, light seen through mirrors and glass, contact shadows, thin mirrors) |

mod build;
mod chrome;
mod grazing;
mod near_light;
mod spheres;
mod terminator;
mod two_lights;

pub use build::{Room, RoomSettings};

/// The rooms of the family.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum RoomKind {
    /// Floating spheres of many sizes and boxes in a 20 x 20 x 8 room, one 4 x 4 light.
    Spheres,
    /// A long low room lit from an end wall, thin shelves, objects on the floor.
    Grazing,
    /// Small curved objects near walls and just under a small bright light; albedo 0.8.
    NearLight,
    /// Two lights of different size and power, a red wall, a sphere on the floor, a slab.
    TwoLights,
    /// One coarse sphere lit at a slant, seen across its terminator.
    Terminator,
    /// Glass, chrome and diffuse balls and thin chrome rings on a plate under strip lights.
    Chrome,
}

impl RoomKind {
    /// Every room, in the order the benchmark reports them.
    pub const ALL: [RoomKind; 6] = [
        RoomKind::Spheres,
        RoomKind::Grazing,
        RoomKind::NearLight,
        RoomKind::TwoLights,
        RoomKind::Terminator,
        RoomKind::Chrome,
    ];

    /// The room's name (its files' stem and its name on the command line).
    pub fn name(self) -> &'static str {
        match self {
            RoomKind::Spheres => "spheres",
            RoomKind::Grazing => "grazing",
            RoomKind::NearLight => "near-light",
            RoomKind::TwoLights => "two-lights",
            RoomKind::Terminator => "terminator",
            RoomKind::Chrome => "chrome",
        }
    }

    /// The room of that [`RoomKind::name`], if any.
    pub fn from_name(name: &str) -> Option<RoomKind> {
        RoomKind::ALL.into_iter().find(|k| k.name() == name)
    }
}

/// Generates the room `kind` with `settings`.
pub fn room(kind: RoomKind, settings: &RoomSettings) -> Room {
    match kind {
        RoomKind::Spheres => spheres::spheres(settings),
        RoomKind::Grazing => grazing::grazing(settings),
        RoomKind::NearLight => near_light::near_light(settings),
        RoomKind::TwoLights => two_lights::two_lights(settings),
        RoomKind::Terminator => terminator::terminator(settings),
        RoomKind::Chrome => chrome::chrome(settings),
    }
}

#[cfg(test)]
mod tests;
