//! The envelope generator's own checks.

use super::*;
use crate::vision::{InspectOptions, Inspection, Verdict, inspect_gray};

/// Renders case `seed` and inspects its image with the case's recipe and
/// the default options (a failed render or inspection fails the test).
fn render_and_inspect(c: &EnvelopeCase, seed: u64) -> (Rendered, Inspection) {
    let r = c.render().unwrap();
    let ins = inspect_gray(
        &c.recipe,
        &r.gray,
        r.info.clone(),
        &InspectOptions::default(),
    )
    .unwrap_or_else(|e| panic!("seed {seed}: {e}"));
    (r, ins)
}

#[test]
fn draws_stay_inside_the_envelope_and_parts_fit() {
    for seed in 0..300 {
        let c = EnvelopeCase::draw(seed);
        let f = &c.factors;
        assert!(
            c.recipe.validate().is_ok(),
            "{seed}: {:?}",
            c.recipe.validate()
        );
        assert!(
            f.mm_per_px >= env::MM_PER_PX.0 - 1e-12 && f.mm_per_px <= env::MM_PER_PX.1 + 1e-12,
            "{seed}: {}",
            f.mm_per_px
        );
        assert!(f.width as u64 * f.height as u64 <= env::MAX_PIXELS);
        assert!(f.width.min(f.height) >= 240 && f.width.max(f.height) >= 320);
        assert!(f.rotation_deg.abs() <= env::ROTATION_DEG);
        assert!((env::CONTRAST.0..=env::CONTRAST.1).contains(&f.contrast));
        assert!((env::GAIN.0..=env::GAIN.1).contains(&f.gain));
        // Every node of the grid inside the frame.
        let sim = c.sim();
        for p in &c.pins {
            let (u, v) = c.pin_uv(p);
            let (x, y) = sim.apply(u, v);
            assert!(
                x > 0.0 && y > 0.0 && x < f.width as f64 && y < f.height as f64,
                "{seed}"
            );
        }
    }
}

#[test]
fn rendered_truth_agrees_with_the_image() {
    // Clean, sharp top-view cases with large tips: each intact tip's
    // intensity centroid (hole level subtracted) over the pixels well
    // inside its clearance hole is its truth centre.
    let mut checked = 0;
    for seed in 0..200 {
        let mut c = EnvelopeCase::draw_with(seed, SizeClass::Small, Some(View::Top));
        if c.factors.tip_px < 12.0 {
            continue;
        }
        c.factors.noise_dn = 0.0;
        c.factors.blur_px = 0.0;
        c.factors.vignetting = 0.0;
        c.factors.gradient = 0.0;
        c.factors.gain = 1.0;
        c.factors.jpeg_quality = None;
        c.factors.colour = false;
        c.factors.bits = 16;
        c.factors.edge_ramp_px = 0.6;
        c.look.shading = 0.0;
        c.look.hole_f = 1.4;
        for p in &mut c.pins {
            p.damage = Damage::None;
            p.present = true;
            p.offset_mm = (0.0, 0.0);
        }
        c.extras.clear();
        let r = c.render().unwrap();
        assert_eq!(r.truth.verdict, Verdict::Pass);
        let m = c.factors.mm_per_px;
        let sim = c.sim();
        let hole_half = 0.5 * c.look.hole_f * c.recipe.pin_mm - 0.7 * m;
        let hole_l = c.contrast_level(c.look.levels.hole) as f64 * 65535.0 / 255.0;
        let sign = if c.recipe.polarity == Polarity::Dark {
            -1.0
        } else {
            1.0
        };
        for t in &r.truth.pins {
            let (tx, ty) = (t.x_px.unwrap(), t.y_px.unwrap());
            let (nu, nv) = c.recipe.nominal_uv_mm(t.row, t.col);
            let reach = (hole_half / m).ceil() as i64 + 2;
            let (mut sw, mut sx, mut sy) = (0.0, 0.0, 0.0);
            for y in (ty.round() as i64 - reach)..=(ty.round() as i64 + reach) {
                for x in (tx.round() as i64 - reach)..=(tx.round() as i64 + reach) {
                    let (u, v) = sim.inverse(x as f64, y as f64);
                    let (du, dv) = (u - nu, v - nv);
                    let inside = match c.recipe.pin_shape {
                        PinShape::Round => du.hypot(dv) < hole_half,
                        PinShape::Square => du.abs() < hole_half && dv.abs() < hole_half,
                    };
                    if !inside {
                        continue;
                    }
                    let v = sign * (r.gray.get(x as u32, y as u32) as f64 - hole_l);
                    sw += v;
                    sx += v * x as f64;
                    sy += v * y as f64;
                }
            }
            assert!(
                (sx / sw - tx).abs() < 0.02 && (sy / sw - ty).abs() < 0.02,
                "seed {seed} {t:?}: {} {}",
                sx / sw,
                sy / sw
            );
        }
        checked += 1;
        if checked == 4 {
            break;
        }
    }
    assert_eq!(checked, 4);
}

#[test]
fn blurred_tips_off_centre_in_their_holes_are_measured_where_they_are() {
    // Heavy defocus, no noise: every intact tip stands 0.8 × position_mm
    // off its hole's centre, in a random direction. The housing's blurred
    // light beside the near side of the hole used to pull the measured
    // centre outward by 0.2–0.4 px (ok pins called bent); the model of the
    // tip in its hole (`blur_tip`) measures it where it is.
    let mut checked = 0;
    let (mut worst, mut worst_band): (f64, f64) = (0.0, 0.0);
    for seed in 0..60 {
        let mut c = EnvelopeCase::draw_with(seed, SizeClass::Small, Some(View::Top));
        if c.factors.tip_px < 7.0 {
            continue;
        }
        c.factors.noise_dn = 0.0;
        c.factors.blur_px = 2.2;
        c.factors.jpeg_quality = None;
        c.recipe.mm_per_px = Some(c.factors.mm_per_px);
        c.extras.clear();
        let tol = c.recipe.tolerance.position_mm;
        for (i, p) in c.pins.iter_mut().enumerate() {
            p.damage = Damage::None;
            p.present = true;
            let a = 2.399 * (i as f64 + seed as f64);
            p.offset_mm = (0.8 * tol * a.cos(), 0.8 * tol * a.sin());
        }
        let (r, ins) = render_and_inspect(&c, seed);
        let cmp = r.compare(&c.factors, &ins);
        assert!(
            cmp.status_mismatches.is_empty(),
            "seed {seed}: {:?}",
            cmp.status_mismatches
        );
        // The guard band between an ok pin (≤ 0.85 × position_mm) and
        // the limit, in px: a centre error inside it cannot flip a status.
        let band_px = 0.15 * tol / c.factors.mm_per_px;
        for e in Rendered::ok_centre_errors(&cmp) {
            worst = worst.max(e);
            worst_band = worst_band.max(e / band_px);
        }
        checked += 1;
        if checked == 6 {
            break;
        }
    }
    assert_eq!(checked, 6);
    eprintln!(
        "blurred off-centre tips: worst ok-pin centre error {worst:.3} px, {worst_band:.2} of the guard band"
    );
    assert!(
        worst_band < 1.0,
        "worst ok-pin centre error {worst:.3} px = {worst_band:.2} × the guard band"
    );
}

#[test]
fn a_side_view_with_every_pin_missing_is_a_failed_connector() {
    let mut checked = 0;
    for seed in 0..40 {
        let mut c = EnvelopeCase::draw_with(seed, SizeClass::Small, Some(View::Side));
        if c.recipe.cols > 3 {
            continue;
        }
        for p in &mut c.pins {
            p.present = false;
        }
        c.extras.clear();
        let (_, ins) = render_and_inspect(&c, seed);
        assert_eq!(ins.verdict, Verdict::Fail, "seed {seed}");
        assert!(
            ins.pins.iter().all(|p| p.status == PinStatus::Missing),
            "seed {seed}"
        );
        assert_eq!(ins.pins.len(), c.pins.len());
        checked += 1;
        if checked == 3 {
            break;
        }
    }
    assert_eq!(checked, 3);
}
