//! The mip pyramid: each level half the one above (rounding down, at least 1), each texel the
//! exact area-weighted mean of what it covers above, so odd sizes lose nothing and every level
//! keeps the image's mean.

use twopass_brdf::Rgb;

use super::raster::MipLevel;

/// The pyramid from `base` down to 1 x 1.
pub(super) fn build(base: MipLevel) -> Vec<MipLevel> {
    let mut levels = vec![base];
    loop {
        let last = levels.last().expect("the base level");
        if last.width == 1 && last.height == 1 {
            return levels;
        }
        let next = halve(last);
        levels.push(next);
    }
}

/// For a side of `from` texels shrunk to `to`, each new texel's source texels and their
/// weights (the fraction of the source texel it covers, times `to / from`, so they sum to 1).
fn weights(from: u32, to: u32) -> Vec<Vec<(u32, f32)>> {
    let ratio = f64::from(from) / f64::from(to);
    (0..to)
        .map(|x| {
            let (a, b) = (f64::from(x) * ratio, f64::from(x + 1) * ratio);
            let mut w = Vec::with_capacity(3);
            let mut s = a.floor() as u32;
            while f64::from(s) < b && s < from {
                let cover = b.min(f64::from(s + 1)) - a.max(f64::from(s));
                if cover > 0.0 {
                    w.push((s, (cover / ratio) as f32));
                }
                s += 1;
            }
            w
        })
        .collect()
}

fn halve(level: &MipLevel) -> MipLevel {
    let (w, h) = ((level.width / 2).max(1), (level.height / 2).max(1));
    let (wx, wy) = (weights(level.width, w), weights(level.height, h));
    let mut texels = Vec::with_capacity(w as usize * h as usize);
    for row in &wy {
        for col in &wx {
            let mut sum = Rgb::ZERO;
            for &(y, fy) in row {
                let line = y as usize * level.width as usize;
                for &(x, fx) in col {
                    sum += level.texels[line + x as usize] * (fx * fy);
                }
            }
            texels.push(sum);
        }
    }
    MipLevel {
        width: w,
        height: h,
        texels,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every level of a 5 x 3 image of distinct values keeps its mean (the exact area weights
    /// over odd sizes), and the pyramid ends at 1 x 1.
    #[test]
    fn every_level_keeps_the_mean() {
        let texels: Vec<Rgb> = (0..15).map(|i| Rgb::splat(i as f32 * i as f32)).collect();
        let mean = texels.iter().copied().sum::<Rgb>() / 15.0;
        let levels = build(MipLevel {
            width: 5,
            height: 3,
            texels,
        });
        let sizes: Vec<(u32, u32)> = levels.iter().map(|l| (l.width, l.height)).collect();
        assert_eq!(sizes, [(5, 3), (2, 1), (1, 1)]);
        for l in &levels {
            let m = l.texels.iter().copied().sum::<Rgb>() / l.texels.len() as f32;
            assert!((m - mean).abs().max_element() < 1e-4, "{m} vs {mean}");
        }
    }
}
