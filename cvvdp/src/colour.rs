//! From display-encoded RGB to the metric's colour space: linear light through the display
//! model, then the DKL opponent space with a D65 white (achromatic, red–green, yellow–violet),
//! by way of the CIE 2006 LMS cone fundamentals.

use crate::display::Display;
use crate::pyramid::Plane;

const XYZ_TO_LMS2006: [[f64; 3]; 3] = [
    [0.187_596_268_556_126, 0.585_168_649_077_728, -0.026_384_263_306_304],
    [-0.133_397_430_663_221, 0.405_505_777_260_049, 0.034_502_127_690_364],
    [0.000_244_379_021_663, -0.000_542_995_890_619, 0.019_406_849_066_323],
];

const LMS2006_TO_DKLD65: [[f64; 3]; 3] =
    [[1.0, 1.0, 0.0], [1.0, -2.311_130_179_947_035, 0.0], [-1.0, -1.0, 50.977_571_328_718_78]];

fn product(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

/// The display's linear RGB → DKLd65, by rows.
pub fn rgb_to_dkl(display: &Display) -> [[f32; 3]; 3] {
    let rgb_to_xyz = display.rgb_to_xyz.map(|row| row.map(f64::from));
    let matrix = product(&product(&LMS2006_TO_DKLD65, &XYZ_TO_LMS2006), &rgb_to_xyz);
    matrix.map(|row| row.map(|v| v as f32))
}

/// A frame of display-encoded RGB (interleaved, row by row, values in [0, 1]) as three DKL
/// planes.
pub fn dkl_planes(display: &Display, width: usize, height: usize, rgb: &[f32]) -> [Plane; 3] {
    let mut planes = std::array::from_fn(|_| Plane::zeros(width, height));
    let matrix = rgb_to_dkl(display);
    // 8-bit code values (k/255, as the runner's frames hold) decode through a table.
    let table: Vec<f32> = (0..=255).map(|k| display.luminance(k as f32 / 255.0)).collect();
    let luminance = |v: f32| {
        let k = (v * 255.0).round();
        if (0.0..=255.0).contains(&k) && k / 255.0 == v { table[k as usize] } else { display.luminance(v) }
    };
    for (i, pixel) in rgb.chunks_exact(3).enumerate() {
        let linear = [luminance(pixel[0]), luminance(pixel[1]), luminance(pixel[2])];
        for (plane, row) in planes.iter_mut().zip(&matrix) {
            plane.data[i] = row[0] * linear[0] + row[1] * linear[1] + row[2] * linear[2];
        }
    }
    planes
}
