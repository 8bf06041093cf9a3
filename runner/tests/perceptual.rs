//! The perceptual metrics against their reference implementations: FLIP (NVIDIA's, through
//! `nv-flip`) against the FLIP team's own Python release, SSIM against scikit-image, on a pair
//! of images that both sides build the same way; identical images score perfectly and more
//! blur scores worse.

use aabench::measure::perceptual::{FLIP_DEFAULT_PIXELS_PER_DEGREE as FLIP_PPD, flip, ssim};
use aabench_renderer::DisplayImage;

const WIDTH: u32 = 64;
const HEIGHT: u32 = 48;
const SIZE: [u32; 2] = [WIDTH, HEIGHT];

/// Ramps in red and green over a checker of 8-pixel cells in blue.
fn pattern() -> Vec<[u8; 3]> {
    (0..HEIGHT)
        .flat_map(|y| {
            (0..WIDTH).map(move |x| {
                let blue = if (x / 8 + y / 8) % 2 == 1 { 255 } else { 0 };
                [((x * 4) % 256) as u8, ((y * 5) % 256) as u8, blue]
            })
        })
        .collect()
}

/// Each pixel the integer mean of itself and its `radius` neighbours on either side in its
/// row, the row's ends repeated.
fn blurred(pixels: &[[u8; 3]], radius: i64) -> Vec<[u8; 3]> {
    let (w, h) = (i64::from(WIDTH), i64::from(HEIGHT));
    (0..h)
        .flat_map(|y| {
            (0..w).map(move |x| {
                let mut sum = [0u32; 3];
                for dx in -radius..=radius {
                    let p = pixels[(y * w + (x + dx).clamp(0, w - 1)) as usize];
                    (0..3).for_each(|c| sum[c] += u32::from(p[c]));
                }
                sum.map(|s| (s / (2 * radius as u32 + 1)) as u8)
            })
        })
        .collect()
}

fn display(pixels: &[[u8; 3]]) -> DisplayImage {
    let bytes: Vec<u8> = pixels.iter().flat_map(|p| [p[0], p[1], p[2], 255]).collect();
    DisplayImage::from_rgba8(&bytes)
}

#[test]
fn identical_images_score_zero_flip_and_unit_ssim() {
    let image = display(&pattern());
    assert_eq!(flip(&image, &image, SIZE, FLIP_PPD).mean(), 0.0);
    assert!((ssim(&image, &image, WIDTH, HEIGHT) - 1.0).abs() < 1e-12);
}

/// The pattern against its three-pixel blur. The reference values were computed from the same
/// pair written as PNG files: FLIP by flip-evaluator 1.7 (`flip_evaluator.evaluate(pattern,
/// blurred, "LDR")`, default 67 pixels per degree), SSIM by scikit-image 0.26
/// (`structural_similarity(blurred, pattern, channel_axis=2, gaussian_weights=True, sigma=1.5,
/// use_sample_covariance=False, data_range=1)`). The FLIP release that `nv-flip` binds is an
/// older one; releases agree to the fourth decimal of the mean, which the FLIP tool prints.
#[test]
fn a_known_pair_matches_the_reference_implementations() {
    let (reference, test) = (display(&pattern()), display(&blurred(&pattern(), 1)));
    let flip_mean = flip(&test, &reference, SIZE, FLIP_PPD).mean();
    assert!((flip_mean - 0.160_607_516_765_594_48).abs() < 1e-4, "FLIP {flip_mean}");
    let ssim_mean = ssim(&test, &reference, WIDTH, HEIGHT);
    assert!((ssim_mean - 0.963_510_883_263_603_3).abs() < 1e-9, "SSIM {ssim_mean}");
}

#[test]
fn more_blur_scores_worse_on_both() {
    let original = display(&pattern());
    let score = |radius| {
        let image = display(&blurred(&pattern(), radius));
        (flip(&image, &original, SIZE, FLIP_PPD).mean(), ssim(&image, &original, WIDTH, HEIGHT))
    };
    let (light, heavy) = (score(1), score(3));
    assert!(heavy.0 > light.0 && light.0 > 0.0, "FLIP: light {}, heavy {}", light.0, heavy.0);
    assert!(heavy.1 < light.1 && light.1 < 1.0, "SSIM: light {}, heavy {}", light.1, heavy.1);
}

#[test]
fn the_flip_map_is_drawn_in_flips_magma_scale() {
    let (reference, test) = (display(&pattern()), display(&blurred(&pattern(), 1)));
    let map = flip(&test, &reference, SIZE, FLIP_PPD);
    let rgba = map.magma_rgba();
    assert_eq!(rgba.len(), 4 * map.errors.len());
    // No error is magma's near-black end; the largest error is drawn bright.
    let (worst, _) = map.errors.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).unwrap();
    let brightness = |i: usize| rgba[4 * i..4 * i + 3].iter().map(|&v| u32::from(v)).sum::<u32>();
    let none = flip(&reference, &reference, SIZE, FLIP_PPD).magma_rgba();
    assert!(none[..3].iter().all(|&v| v < 8), "{:?}", &none[..3]);
    assert!(brightness(worst) > 200);
}
