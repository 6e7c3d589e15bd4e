//! Unit tests of `interp::preview` (`src/interp/preview.rs`).

use vstructc::interp::preview::*;

/// The span holds exactly the columns whose centres pass `on_sphere`, at odd and even
/// sizes, including the rows that graze the sphere or miss it.
#[test]
fn sphere_span_is_the_set_on_the_sphere() {
    for size in (1..=80).chain([255, 256, 511, 512, 513]) {
        for j in 0..size {
            let want: Vec<usize> = (0..size)
                .filter(|&i| {
                    let (x, y) = pixel_xy(i, j, size);
                    on_sphere(x, y)
                })
                .collect();
            let got: Vec<usize> = sphere_span(j, size).collect();
            assert_eq!(got, want, "size {size}, row {j}");
        }
    }
}
