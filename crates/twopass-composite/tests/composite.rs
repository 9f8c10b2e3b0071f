//! Cross-module checks: EXR round trips, refused writes, sheet layout and pixels.

use std::path::Path;

use glam::Vec3;
use twopass_composite::error::CompositeError;
use twopass_composite::false_colour::{ErrorKind, ErrorMap, Palette, Scale};
use twopass_composite::image::{Image, Rect, Rgb8Image};
use twopass_composite::layer::{FINAL, Layers};
use twopass_composite::sheet::{
    self, BACKGROUND, BAR_LABELS, BAR_WIDTH, CAPTION_PAD, Entry, GAP, LINE, MARGIN, Panel, Row,
    Sheet, TITLE_LINE,
};
use twopass_composite::tonemap::ToneMap;
use twopass_composite::write;
use twopass_tests::{exr_text, file_names};

fn ramp(w: u32, h: u32, k: f32) -> Image {
    Image::from_fn(w, h, |x, y| {
        // Values that are not round in binary, plus one large and one tiny value.
        [
            k * (x as f32 + 0.1) / 3.0,
            k * (y as f32).sqrt() * 1.7e3,
            k * 1e-7 * (x + y) as f32,
        ]
    })
}

/// A `width` x `height` layer set of [`ramp`]s, one per (name, scale), in order.
fn ramps(width: u32, height: u32, layers: &[(&str, f32)]) -> Layers {
    let mut set = Layers::new(width, height);
    for &(name, k) in layers {
        set = set.with(name, ramp(width, height, k)).unwrap();
    }
    set
}
#[test]
fn multi_layer_exr_round_trip_is_bit_identical() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cornell.exr");
    let mut layers = ramps(7, 5, &[("radiosity", 1.0), ("specular", 0.25)]);
    layers
        .merge_into(FINAL, &["radiosity", "specular"])
        .unwrap();
    write::write_exr_layers(&path, &layers).unwrap();

    // Read back with the exr crate directly: one part, channels <layer>.R/G/B.
    let raw = exr::prelude::read_all_flat_layers_from_file(&path).unwrap();
    assert_eq!(raw.layer_data.len(), 1);
    let names: Vec<String> = raw.layer_data[0]
        .channel_data
        .list
        .iter()
        .map(|c| c.name.to_string())
        .collect();
    for l in ["final", "radiosity", "specular"] {
        for c in ["R", "G", "B"] {
            assert!(names.contains(&format!("{l}.{c}")), "{names:?}");
        }
    }

    let back = write::read_exr_layers(&path).unwrap();
    assert_eq!(
        back.names().collect::<Vec<_>>(),
        ["final", "radiosity", "specular"]
    );
    for (name, image) in layers.iter() {
        let b = back.get(name).unwrap();
        assert_eq!(b.size(), image.size());
        for (p, q) in image.pixels().iter().zip(b.pixels()) {
            for c in 0..3 {
                assert_eq!(p[c].to_bits(), q[c].to_bits(), "layer {name}");
            }
        }
    }

    // A single image: plain R, G, B.
    let single = dir.path().join("one.exr");
    write::write_exr(&single, layers.get("specular").unwrap()).unwrap();
    assert_eq!(
        &write::read_exr(&single).unwrap(),
        layers.get("specular").unwrap()
    );
    assert_eq!(file_names(dir.path()), ["cornell.exr", "one.exr"]);
}

#[test]
fn non_finite_pixels_are_refused_and_nothing_is_left() {
    let dir = tempfile::tempdir().unwrap();
    let mut bad = ramp(4, 3, 1.0);
    bad.set(2, 1, Vec3::new(0.0, f32::NAN, 1.0));
    let layers = Layers::new(4, 3)
        .with("good", ramp(4, 3, 1.0))
        .unwrap()
        .with("broken", bad.clone())
        .unwrap();
    let path = dir.path().join("out.exr");
    match write::write_exr_layers(&path, &layers) {
        Err(CompositeError::NonFinite {
            path: Some(p),
            layer: Some(l),
            x: 2,
            y: 1,
            ..
        }) => {
            assert_eq!(p, path);
            assert_eq!(l, "broken");
        }
        other => panic!("{other:?}"),
    }
    let err = write::write_exr(&path, &bad).unwrap_err();
    assert!(err.to_string().contains("out.exr"), "{err}");
    let png = dir.path().join("out.png");
    let mut inf = ramp(4, 3, 1.0);
    inf.set(0, 0, Vec3::splat(f32::INFINITY));
    assert!(matches!(
        write::write_png_tonemapped(&png, &inf, &ToneMap::default()),
        Err(CompositeError::NonFinite { .. })
    ));
    assert!(
        file_names(dir.path()).is_empty(),
        "{:?}",
        file_names(dir.path())
    );

    // An existing file is left as it was by a refused write.
    write::write_exr(&path, &ramp(4, 3, 2.0)).unwrap();
    let before = std::fs::read(&path).unwrap();
    assert!(write::write_exr(&path, &bad).is_err());
    assert_eq!(std::fs::read(&path).unwrap(), before);
    assert_eq!(file_names(dir.path()), ["out.exr"]);
}

#[test]
fn png_is_tone_mapped_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("t.png");
    let img = Image::from_fn(3, 2, |x, y| [x as f32 * 0.25, y as f32 * 0.5, 0.5]);
    let map = ToneMap::from_stops(1.0).unwrap();
    write::write_png_tonemapped(&path, &img, &map).unwrap();
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let text = reader.info().uncompressed_latin1_text.clone();
    assert!(
        text.iter()
            .any(|t| t.keyword == "Description" && t.text.contains("+1.00 EV"))
    );
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    reader.next_frame(&mut buf).unwrap();
    assert_eq!(&buf[..], map.apply(&img).data());
    // Pixel (1, 0): red 0.25 * 2 = 0.5 -> sRGB 0.7354 -> 188.
    assert_eq!(buf[3], 188);
}

fn solid(w: u32, h: u32, c: [u8; 3]) -> Rgb8Image {
    Rgb8Image::from_fn(w, h, |x, y| {
        [c[0].wrapping_add(x as u8), c[1].wrapping_add(y as u8), c[2]]
    })
}

#[test]
fn sheet_layout_and_panel_pixels() {
    let a = solid(40, 30, [10, 20, 30]);
    let b = solid(50, 20, [200, 100, 0]);
    let c = solid(40, 25, [0, 250, 90]);
    let scale = Scale::new(0.0, 0.5, Palette::Viridis, ErrorKind::Absolute).unwrap();
    let s = Sheet {
        title: Some("Title".into()),
        rows: vec![
            Row {
                cells: vec![
                    Some(Panel {
                        image: a.clone(),
                        caption: vec!["a".into(), "1.0 s".into()],
                    }),
                    Some(Panel {
                        image: b.clone(),
                        caption: vec!["b".into()],
                    }),
                ],
                bar: None,
            },
            Row {
                cells: vec![
                    None,
                    Some(Panel {
                        image: c.clone(),
                        caption: vec![],
                    }),
                ],
                bar: Some(scale),
            },
        ],
        footer: vec!["footer".into()],
    };
    let (img, l) = s.render().unwrap();
    // Columns 40 and 50 wide; captions of 2 lines everywhere.
    let cap = CAPTION_PAD + 2 * LINE;
    assert_eq!(
        l.width,
        MARGIN + 40 + GAP + 50 + GAP + BAR_WIDTH + BAR_LABELS + MARGIN
    );
    let row0 = MARGIN + TITLE_LINE;
    let row1 = row0 + 30 + cap + GAP;
    assert_eq!(l.height, row1 + 25 + cap + LINE + GAP + MARGIN);
    assert_eq!(img.size(), (l.width, l.height));
    assert_eq!(l.panels[0][0], Some(Rect::new(MARGIN, row0, 40, 30)));
    assert_eq!(
        l.panels[0][1],
        Some(Rect::new(MARGIN + 40 + GAP, row0, 50, 20))
    );
    assert_eq!(l.panels[1][0], None);
    assert_eq!(
        l.panels[1][1],
        Some(Rect::new(MARGIN + 40 + GAP, row1, 40, 25))
    );
    assert_eq!(
        l.bars[1],
        Some(Rect::new(MARGIN + 40 + GAP + 50 + GAP, row1, BAR_WIDTH, 25))
    );
    for (r, src) in [
        (l.panels[0][0], &a),
        (l.panels[0][1], &b),
        (l.panels[1][1], &c),
    ] {
        assert_eq!(&img.crop(r.unwrap()).unwrap(), src);
    }
    // Captions hold ink, and never reach into a panel.
    let cap0 = l.captions[0][0].unwrap();
    assert!(
        img.crop(cap0)
            .unwrap()
            .data()
            .chunks(3)
            .any(|p| p != BACKGROUND)
    );
    let all: Vec<Rect> = l.panels.iter().flatten().flatten().copied().collect();
    for (i, p) in all.iter().enumerate() {
        for q in &all[i + 1..] {
            assert!(!p.overlaps(q));
        }
        for c in l.captions.iter().flatten().flatten() {
            assert!(!p.overlaps(c));
        }
    }
    // The bar is the palette, max at the top.
    let bar = l.bars[1].unwrap();
    assert_eq!(img.get(bar.x, bar.y), Palette::Viridis.colour(1.0));
    assert_eq!(
        img.get(bar.x, bar.y + bar.height - 1),
        Palette::Viridis.colour(0.0)
    );
}

/// A small Cornell-like scene, rendered as three "methods" with different errors.
fn box_image(w: u32, h: u32, noise: f32, bias: f32) -> Image {
    Image::from_fn(w, h, |x, y| {
        let (u, v) = (x as f32 / w as f32, y as f32 / h as f32);
        let wall = if u < 0.15 {
            Vec3::new(0.6, 0.06, 0.05)
        } else if u > 0.85 {
            Vec3::new(0.1, 0.45, 0.08)
        } else {
            Vec3::splat(0.55)
        };
        let light = if v < 0.06 && (0.4..0.6).contains(&u) {
            Vec3::splat(20.0)
        } else {
            Vec3::ZERO
        };
        let shade = 0.4 + 0.6 * (1.0 - v) + bias * u;
        let hash = ((x.wrapping_mul(73_856_093) ^ y.wrapping_mul(19_349_663)) % 1000) as f32
            / 1000.0
            - 0.5;
        light + wall * shade * (1.0 + noise * hash)
    })
}

#[test]
fn comparison_sheet_shares_exposure_and_scale() {
    let (w, h) = (96, 96);
    let reference = box_image(w, h, 0.0, 0.0);
    let noisy = box_image(w, h, 0.3, 0.0);
    let biased = box_image(w, h, 0.0, 0.3);
    let r = Entry {
        method: "reference",
        image: &reference,
        seconds: Some(22.0),
    };
    let others = [
        Entry {
            method: "path tracer",
            image: &noisy,
            seconds: Some(4.8),
        },
        Entry {
            method: "hybrid",
            image: &biased,
            seconds: Some(0.41),
        },
    ];
    let opts = sheet::ComparisonOptions {
        title: Some("Cornell box (synthetic)".into()),
        ..Default::default()
    };
    let c = sheet::comparison(&r, &others, &opts).unwrap();
    // One exposure, from the reference; every render panel is that tone map of its image.
    assert_eq!(c.tone_map, ToneMap::auto_default(&reference).unwrap());
    for (i, img) in [&reference, &noisy, &biased].into_iter().enumerate() {
        let rect = c.layout.panels[0][i].unwrap();
        assert_eq!(c.image.crop(rect).unwrap(), c.tone_map.apply(img));
    }
    // One scale; every difference panel is that scale applied to its error map.
    for (i, img) in [&noisy, &biased].into_iter().enumerate() {
        let rect = c.layout.panels[1][i + 1].unwrap();
        let map = ErrorMap::new(img, &reference, ErrorKind::Relative).unwrap();
        assert_eq!(c.image.crop(rect).unwrap(), c.scale.apply(&map));
    }
    assert!(c.metrics[0].rel_rmse > 0.0 && c.metrics[1].ssim < 1.0);
    if let Ok(dir) = std::env::var("TWOPASS_COMPOSITE_SHEET_DIR") {
        write::write_png(
            &Path::new(&dir).join("comparison_sheet.png"),
            &c.image,
            Some(&c.describe),
        )
        .unwrap();
    }
}

#[test]
fn render_exr_has_the_final_image_as_plain_rgb_and_its_metadata() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("render.exr");
    let mut layers = ramps(
        6,
        4,
        &[("ambient", 0.0), ("diffuse", 1.0), ("specular", 0.5)],
    );
    layers
        .merge_into(write::IMAGE, &["diffuse", "specular"])
        .unwrap();
    let meta = twopass_composite::RenderMetadata::new("hybrid", 16, 42, 1.25);
    write::write_exr_render(&path, &layers, &meta).unwrap();

    // Read back with the exr crate itself: plain R, G, B equal to the `image` layer, the
    // passes beside it, the metadata in the header.
    let raw = exr::prelude::read_all_flat_layers_from_file(&path).unwrap();
    assert_eq!(raw.layer_data.len(), 1);
    let layer = &raw.layer_data[0];
    let channel = |name: &str| -> Vec<f32> {
        layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.to_string() == name)
            .unwrap_or_else(|| panic!("no channel {name}"))
            .sample_data
            .values_as_f32()
            .collect()
    };
    let image = layers.get(write::IMAGE).unwrap();
    for (c, letter) in ["R", "G", "B"].into_iter().enumerate() {
        let top = channel(letter);
        let expect: Vec<f32> = image.pixels().iter().map(|p| p[c]).collect();
        assert_eq!(top, expect, "channel {letter}");
        for pass in ["ambient", "diffuse", "specular", "image"] {
            channel(&format!("{pass}.{letter}"));
        }
    }
    let attr = |name: &str| exr_text(&layer.attributes, name);
    assert_eq!(attr("twopass:method"), "hybrid");
    assert_eq!(attr("twopass:spp"), "16");
    assert_eq!(attr("twopass:seed"), "42");
    assert_eq!(attr("twopass:seconds"), "1.25");
    assert_eq!(attr("twopass:version"), env!("CARGO_PKG_VERSION"));
    assert_eq!(
        layer
            .attributes
            .software_name
            .as_ref()
            .map(|t| t.to_string()),
        Some(format!("twopass {}", env!("CARGO_PKG_VERSION")))
    );
    // The plain image is what read_exr returns, and the layers still read back as layers.
    assert_eq!(&write::read_exr(&path).unwrap(), image);
    let back = write::read_exr_layers(&path).unwrap();
    assert_eq!(
        back.names().collect::<Vec<_>>(),
        ["ambient", "diffuse", "image", "specular"]
    );

    // Without a merged layer, the plain image is the sum of the passes.
    let passes = ramps(6, 4, &[("a", 1.0), ("b", 0.25)]);
    let summed = dir.path().join("passes.exr");
    write::write_exr_layers(&summed, &passes).unwrap();
    let top = write::read_exr(&summed).unwrap();
    for ((p, a), b) in top
        .pixels()
        .iter()
        .zip(passes.get("a").unwrap().pixels())
        .zip(passes.get("b").unwrap().pixels())
    {
        assert_eq!(*p, *a + *b);
    }
}
