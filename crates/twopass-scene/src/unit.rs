//! The length unit a scene file states (`unit = "mm"`): what one scene unit is in metres, for
//! outputs whose format fixes its unit (glTF is in metres).

use serde::Deserialize;

/// The length unit of a scene's positions, from the scene file's top-level `unit` key
/// (`"mm"`, `"cm"`, `"m"`, `"in"`, `"ft"`; default metres; a bare OBJ is in metres). It
/// changes no computation: positions, areas and the solution stay in scene units. It tells
/// exporters how to convert to a format's own unit ([`Unit::metres`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Deserialize)]
pub enum Unit {
    /// Millimetre, `"mm"`: 0.001 m.
    #[serde(rename = "mm")]
    Millimetre,
    /// Centimetre, `"cm"`: 0.01 m.
    #[serde(rename = "cm")]
    Centimetre,
    /// Metre, `"m"` (the default).
    #[default]
    #[serde(rename = "m")]
    Metre,
    /// International inch, `"in"`: 0.0254 m.
    #[serde(rename = "in")]
    Inch,
    /// International foot, `"ft"`: 0.3048 m.
    #[serde(rename = "ft")]
    Foot,
}

impl Unit {
    /// Every unit, in the order the scene format documents them.
    pub const ALL: [Self; 5] = [
        Self::Millimetre,
        Self::Centimetre,
        Self::Metre,
        Self::Inch,
        Self::Foot,
    ];

    /// Length of one scene unit in metres (exact by definition of each unit).
    pub fn metres(self) -> f64 {
        match self {
            Self::Millimetre => 0.001,
            Self::Centimetre => 0.01,
            Self::Metre => 1.0,
            Self::Inch => 0.0254,
            Self::Foot => 0.3048,
        }
    }

    /// The symbol the scene file uses (`"mm"`, ...).
    pub fn symbol(self) -> &'static str {
        match self {
            Self::Millimetre => "mm",
            Self::Centimetre => "cm",
            Self::Metre => "m",
            Self::Inch => "in",
            Self::Foot => "ft",
        }
    }
}

impl std::fmt::Display for Unit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.symbol())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn symbols_parse_back_to_their_unit() {
        #[derive(Deserialize)]
        struct T {
            unit: Unit,
        }
        for u in Unit::ALL {
            let t: T = toml::from_str(&format!("unit = \"{}\"", u.symbol())).unwrap();
            assert_eq!(t.unit, u);
        }
        // Inch and foot by their definitions (1959): 12 in = 1 ft, 1 in = 25.4 mm.
        assert!((Unit::Foot.metres() - 12.0 * Unit::Inch.metres()).abs() < 1e-15);
        assert!((Unit::Inch.metres() - 25.4 * Unit::Millimetre.metres()).abs() < 1e-15);
    }
}
