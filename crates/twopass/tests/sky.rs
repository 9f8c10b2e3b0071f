//! The sky through the command line: bad `[sky]` and `[[portal]]` tables exit 1 with the
//! file, line, table and key; `info` says whether the sky is in use and plans a scene lit by
//! the sky alone, which renders and is not refused as unlit.

use crate::common::{assert_ok, ok_json, twopass};
use crate::lamps::{floor_with, info_fails, renders_lit, write};

#[test]
fn bad_sky_tables_exit_1_naming_the_line_table_and_key() {
    let dir = tempfile::tempdir().unwrap();
    // The [sky] table starts at line 15.
    #[rustfmt::skip]
    let cases = [
        ("[sky]\nkind = \"daylight\"\nsun_elevation = 30\nturbidity = 1\n",
         ":15: sky: `turbidity` must be in [2, 10], where the daylight model is fitted (got 1)"),
        ("[sky]\nkind = \"daylight\"\nsun_elevation = 30\nsun_diameter = 90\n",
         ":15: sky: `sun_diameter` must be in (0, 45] degrees (got 90)"),
        ("[sky]\nkind = \"daylight\"\nsun_direction = [0, 1, 0]\nsun_elevation = 30\n",
         ":15: sky: give exactly one of `sun_elevation` (degrees, with `sun_azimuth`) and `sun_direction`"),
        ("[sky]\nkind = \"uniform\"\nradiance = [1, 1, -3]\n",
         ":15: sky: `radiance` channel 2 must be finite and non-negative (got -3 W/(m^2 sr))"),
        ("[sky]\nkind = \"uniform\"\nradiance = 1\n[[portal]]\norigin = [0, 1, 0]\nedge_u = [0, 0, 0]\nedge_v = [1, 0, 0]\n",
         ":18: portal 1: `edge_u` and `edge_v` are parallel or zero: the portal has no area"),
        ("[[portal]]\norigin = [0, 1, 0]\nedge_u = [1, 0, 0]\nedge_v = [0, 0, 1]\n",
         ":15: portal 1: `[[portal]]` needs a `[sky]` table (a portal only lets the sky in)"),
    ];
    for (bad, expected) in cases {
        info_fails(dir.path(), bad, expected);
    }
}

#[test]
fn info_says_when_the_sky_is_in_use_and_a_sky_alone_lights_a_render() {
    let dir = tempfile::tempdir().unwrap();
    let without = write(
        dir.path(),
        &floor_with("[[light]]\nkind = \"point\"\nposition = [0, 1, 0]\nintensity = 1\n"),
    );
    let v = ok_json(&twopass(&["info", without.to_str().unwrap(), "--json"]));
    assert_eq!(v["plan"]["sky"]["required"], false);
    assert_eq!(
        v["plan"]["sky"]["reason"],
        "no [sky] table: rays that leave the scene see black"
    );
    let path = write(
        dir.path(),
        &floor_with(
            "[sky]\nkind = \"daylight\"\nturbidity = 3\nsun_elevation = 40\nscale = 0.001\n\
             [[portal]]\norigin = [-1, 1, -1]\nedge_u = [2, 0, 0]\nedge_v = [0, 0, 2]\n",
        ),
    );
    let out = twopass(&["info", path.to_str().unwrap()]);
    assert_ok(&out);
    let text = String::from_utf8_lossy(&out.stdout);
    for line in [
        "diffuse pass      required: 1 diffusely reflecting object(s) lit by 0 emitter(s), 0 lamp(s) and the sky",
        "sky               required: daylight (Preetham), turbidity 3, sun elevation 40.0 deg, sun 0.53 deg wide,",
        "scale 0.001, 1 portal",
    ] {
        assert!(text.contains(line), "{line}\n{text}");
    }
    let v = ok_json(&twopass(&["info", path.to_str().unwrap(), "--json"]));
    assert_eq!(v["plan"]["sky"]["required"], true);
    renders_lit(dir.path(), &path, &["radiosity", "hybrid", "reference"]);
}
