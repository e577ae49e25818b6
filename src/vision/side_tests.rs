//! Unit tests of `vision::side` through the whole side-view pipeline
//! (beside it, so the module reads on its own).

use super::super::gray::{Gray, GrayData};
use super::super::{InspectOptions, PinStatus, Recipe, inspect_gray};

/// A 1 × 8 row at 0.05 mm/px (pins 7 px wide, so the coarse factor is 1):
/// backlight 200, silhouette 60, the housing's edge at the pixel boundary
/// y = 100, every pin's end at y = 60 (2.0 mm, the nominal height), pin j
/// over columns 47 + 20 j .. 53 + 20 j.
fn row_image() -> (usize, usize, Vec<u8>) {
    let (w, h) = (240usize, 160usize);
    let mut d = vec![200u8; w * h];
    for y in 100..h {
        d[y * w + 20..y * w + 220].fill(60);
    }
    for j in 0..8 {
        let c = 47 + 20 * j;
        for y in 60..100 {
            d[y * w + c..y * w + c + 7].fill(60);
        }
    }
    (w, h, d)
}

fn recipe() -> Recipe {
    Recipe::from_toml_str(
        "part_number = \"S\"\nview = \"side\"\nrows = 1\ncols = 8\npitch_mm = [1.0, 1.0]\npin_mm = 0.35\npin_shape = \"square\"\npolarity = \"dark\"\nmm_per_px = 0.05\n[tolerance]\nposition_mm = 0.1\nheight_mm = 2.0\nheight_tol_mm = 0.1\n",
        "s",
    )
    .unwrap()
}

/// Single dark noise pixels just above the edge, 4 px left of pins 2 and
/// 5, stood on the edge and were taken for bars; they left those pins too
/// little backlight beside them and both were called missing. Every pin
/// is ok at 2.0 mm and nothing is an extra.
#[test]
fn a_speck_beside_a_pin_on_the_edge_is_no_bar() {
    let (w, h, mut d) = row_image();
    for j in [2, 5] {
        d[98 * w + 47 + 20 * j - 4] = 60;
    }
    let g = Gray {
        width: w as u32,
        height: h as u32,
        data: GrayData::U8(d),
    };
    let ins = inspect_gray(
        &recipe(),
        &g,
        Default::default(),
        &InspectOptions::default(),
    )
    .unwrap();
    for p in &ins.pins {
        assert_eq!(p.status, PinStatus::Ok, "{p:?}");
        assert!((p.height_mm.unwrap() - 2.0).abs() < 0.02, "{p:?}");
        assert!(
            (p.x_px.unwrap() - (50.0 + 20.0 * p.col as f64)).abs() < 0.05,
            "{p:?}"
        );
    }
    assert!(ins.extras.is_empty(), "{:?}", ins.extras);
}
