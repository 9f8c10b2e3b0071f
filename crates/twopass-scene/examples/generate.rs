//! Writes the synthetic benchmark scene (the Cornell room filled with icospheres, as
//! `twopass bench rays --generate` and `twopass bench radiosity --generate` build it) as a
//! scene file, so that any command can run on it.
//!
//! `cargo run --release -p twopass-scene --example generate -- 100000 > room-100k.toml`

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let triangles: usize = args.next().map_or(Ok(100_000), |s| s.parse())?;
    let seed: u64 = args.next().map_or(Ok(0), |s| s.parse())?;
    print!(
        "{}",
        twopass_scene::workload::synthetic_scene_toml(triangles, seed)
    );
    Ok(())
}
