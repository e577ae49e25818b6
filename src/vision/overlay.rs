//! The annotated overlay: the image with the fitted grid, every pin
//! coloured by its status, offsets magnified, tolerance circles, extras and
//! the housing. Drawn into an `image::RgbImage`; the PNG writer of
//! `pinsight inspect` and the TUI's Vision pane both use [`draw_overlay`].
//!
//! Legend: green ok, red missing, magenta damaged, orange bent, blue short,
//! purple high; extras are red squares, ignored blobs grey squares; thin
//! cyan lines join the nominal positions; each pin's offset is drawn from its
//! nominal position magnified `magnify` times, with the position tolerance
//! (also magnified) as a circle, so an arrow leaving its circle is a bent
//! pin.

use super::gray::Gray;
use super::recipe::View;
use super::result::{Inspection, PinStatus, Verdict};
use ab_glyph::FontRef;
use image::{Rgb, RgbImage};
use imageproc::drawing::{
    draw_filled_rect_mut, draw_hollow_circle_mut, draw_hollow_rect_mut, draw_line_segment_mut,
    draw_text_mut,
};
use imageproc::rect::Rect;

use crate::plot::FONT;

/// Colour of a status on the overlay (also for the TUI's table).
pub fn status_colour(s: PinStatus) -> [u8; 3] {
    match s {
        PinStatus::Ok => [40, 200, 60],
        PinStatus::Missing => [230, 40, 40],
        PinStatus::Damaged => [220, 60, 220],
        PinStatus::Bent => [255, 150, 0],
        PinStatus::Short => [60, 120, 255],
        PinStatus::High => [150, 80, 255],
    }
}

/// Drawing options.
#[derive(Debug, Clone)]
pub struct OverlayOptions {
    /// Offset magnification (the tolerance circle uses the same factor).
    pub magnify: f64,
    /// Draw the caption (part, verdict, counts).
    pub caption: bool,
    /// Dim the image so the annotations stand out (0 = black, 1 = as is).
    pub brightness: f32,
}

impl Default for OverlayOptions {
    fn default() -> Self {
        Self {
            magnify: 10.0,
            caption: true,
            brightness: 0.8,
        }
    }
}

fn px(c: [u8; 3]) -> Rgb<u8> {
    Rgb(c)
}

/// The image as RGB (display-stretched grey, dimmed).
pub fn base_image(gray: &Gray, brightness: f32) -> RgbImage {
    let g = gray.to_display_u8();
    let mut out = RgbImage::new(g.width(), g.height());
    for (o, p) in out.pixels_mut().zip(g.pixels()) {
        let v = (p.0[0] as f32 * brightness).round().clamp(0.0, 255.0) as u8;
        *o = Rgb([v, v, v]);
    }
    out
}

/// Draws the overlay of `ins` on `gray`.
pub fn draw_overlay(gray: &Gray, ins: &Inspection, opts: &OverlayOptions) -> RgbImage {
    let mut img = base_image(gray, opts.brightness);
    annotate(&mut img, ins, opts);
    img
}

/// Draws the annotations of `ins` onto an existing RGB image of the same
/// geometry (e.g. a cached base image in the TUI).
pub fn annotate(img: &mut RgbImage, ins: &Inspection, opts: &OverlayOptions) {
    let (w, h) = (img.width() as f32, img.height() as f32);
    let scale = (w.max(h) / 1024.0).max(0.6);
    let lw = scale.round().max(1.0) as i32;
    let line = |img: &mut RgbImage, a: (f64, f64), b: (f64, f64), c: [u8; 3]| {
        for d in 0..lw {
            let o = d as f32 - (lw - 1) as f32 / 2.0;
            draw_line_segment_mut(
                img,
                (a.0 as f32 + o, a.1 as f32),
                (b.0 as f32 + o, b.1 as f32),
                px(c),
            );
            draw_line_segment_mut(
                img,
                (a.0 as f32, a.1 as f32 + o),
                (b.0 as f32, b.1 as f32 + o),
                px(c),
            );
        }
    };
    let mm_per_px = ins.grid.mm_per_px;
    let pin_px = {
        // Tip size on screen from the grid spacing: a quarter pitch.
        let mut d = f64::INFINITY;
        for (i, p) in ins.pins.iter().enumerate() {
            for q in ins.pins.iter().skip(i + 1) {
                d = d.min((p.nominal_x_px - q.nominal_x_px).hypot(p.nominal_y_px - q.nominal_y_px));
            }
        }
        if d.is_finite() { 0.3 * d } else { 20.0 }
    };
    // Housing.
    if let Some(hs) = &ins.housing {
        let c = hs.corners_px;
        for i in 0..4 {
            line(img, c[i], c[(i + 1) % 4], [230, 200, 40]);
        }
    }
    // Grid lines through nominal positions (rows and columns).
    let grid_c = [0, 170, 200];
    for p in &ins.pins {
        if let Some(q) = ins
            .pins
            .iter()
            .find(|q| q.row == p.row && q.col == p.col + 1)
        {
            line(
                img,
                (p.nominal_x_px, p.nominal_y_px),
                (q.nominal_x_px, q.nominal_y_px),
                grid_c,
            );
        }
        if let Some(q) = ins
            .pins
            .iter()
            .find(|q| q.row == p.row + 1 && q.col == p.col)
        {
            line(
                img,
                (p.nominal_x_px, p.nominal_y_px),
                (q.nominal_x_px, q.nominal_y_px),
                grid_c,
            );
        }
    }
    let tol_px = match ins.view {
        View::Top | View::Side => ins
            .pins
            .first()
            .map(|_| opts.magnify * tolerance_guess(ins) / mm_per_px)
            .unwrap_or(0.0),
    };
    for p in &ins.pins {
        let c = status_colour(p.status);
        let n = (p.nominal_x_px, p.nominal_y_px);
        let half = (pin_px / 2.0).max(3.0);
        match (p.x_px, p.y_px) {
            (Some(x), Some(y)) => {
                let r = Rect::at((x - half) as i32, (y - half) as i32)
                    .of_size((2.0 * half) as u32, (2.0 * half) as u32);
                for d in 0..lw {
                    let rr = Rect::at(r.left() - d, r.top() - d)
                        .of_size(r.width() + 2 * d as u32, r.height() + 2 * d as u32);
                    draw_hollow_rect_mut(img, rr, px(c));
                }
                // Magnified offset from nominal.
                let e = (
                    n.0 + opts.magnify * (x - n.0),
                    n.1 + opts.magnify * (y - n.1),
                );
                line(img, n, e, c);
            }
            _ => {
                // Missing: a cross at the nominal position.
                line(img, (n.0 - half, n.1 - half), (n.0 + half, n.1 + half), c);
                line(img, (n.0 - half, n.1 + half), (n.0 + half, n.1 - half), c);
            }
        }
        if tol_px > 1.0 {
            draw_hollow_circle_mut(
                img,
                (n.0.round() as i32, n.1.round() as i32),
                tol_px.round() as i32,
                px([0, 170, 200]),
            );
        }
    }
    for e in &ins.extras {
        let s = (pin_px / 2.0).max(4.0);
        let r = Rect::at((e.x_px - s) as i32, (e.y_px - s) as i32)
            .of_size((2.0 * s) as u32, (2.0 * s) as u32);
        for d in 0..(lw + 1) {
            let rr = Rect::at(r.left() - d, r.top() - d)
                .of_size(r.width() + 2 * d as u32, r.height() + 2 * d as u32);
            draw_hollow_rect_mut(img, rr, px([255, 30, 30]));
        }
    }
    for e in &ins.ignored {
        let s = (pin_px / 3.0).max(3.0);
        let r = Rect::at((e.x_px - s) as i32, (e.y_px - s) as i32)
            .of_size((2.0 * s) as u32, (2.0 * s) as u32);
        draw_hollow_rect_mut(img, r, px([150, 150, 150]));
    }
    if opts.caption {
        let Ok(font) = FontRef::try_from_slice(FONT) else {
            return;
        };
        let size = 18.0 * scale;
        let verdict = match ins.verdict {
            Verdict::Pass => "PASS",
            Verdict::Fail => "FAIL",
        };
        let vc = match ins.verdict {
            Verdict::Pass => [40, 200, 60],
            Verdict::Fail => [230, 40, 40],
        };
        let c = &ins.counts;
        let text = format!(
            "{verdict}  {}  ok {} missing {} damaged {} bent {} short {} high {} extras {}  (offsets x{})",
            ins.part_number,
            c.ok,
            c.missing,
            c.damaged,
            c.bent,
            c.short,
            c.high,
            ins.extras.len(),
            opts.magnify
        );
        let (tw, th) = imageproc::drawing::text_size(size, &font, &text);
        draw_filled_rect_mut(
            img,
            Rect::at(0, 0).of_size((tw + 12).min(img.width()), th + 10),
            px([0, 0, 0]),
        );
        draw_text_mut(img, px(vc), 6, 4, size, &font, &text);
    }
}

fn tolerance_guess(ins: &Inspection) -> f64 {
    ins.tolerance.position_mm
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colours_are_distinct() {
        let mut v: Vec<[u8; 3]> = PinStatus::ALL.iter().map(|s| status_colour(*s)).collect();
        v.sort();
        v.dedup();
        assert_eq!(v.len(), PinStatus::ALL.len());
    }
}
