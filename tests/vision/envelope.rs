//! Verdict accuracy over the randomised imaging envelope
//! (`vision::synth_envelope`): every factor drawn at once, exact truth,
//! a look unlike our own `synth::Scene`. Seeds 200 000 … 200 239 are
//! held out: the pipeline was tuned on 0 … 999 (`examples/eval_envelope`).
//!
//! The floors below are a **ratchet at the level last measured**, less a
//! small margin (2026-11-24: 90.0 % verdicts, 98.14 % pin statuses, 6
//! errors, median 0.081 px on these 240; 2026-11-25: 91.2 %, 98.43 %, 4
//! errors, 0.080 px; 2026-11-26: 91.7 %, 98.43 %, 4 errors, 0.080 px; after the
//! scale cross-check, 2026-11-26: 91.7 %, 98.36 %, 5 errors, 0.080 px, seed
//! 200 133 newly an error, see docs/vision.md; after the component-tree split
//! of tip blobs, the side view's bar rule and the generator's gradient
//! levelled off beyond the part, 2026-11-26: 93.75 %, 99.11 %, 1 error,
//! 0.081 px; after the model-fitted centres of blurred tips, 2026-11-26:
//! 95.4 %, 99.30 %, 1 error, 0.069 px; after debris on the housing's edge
//! is cut from the brighter fixture it touches, 2026-11-26: 95.8 %,
//! 99.30 %, 1 error, 0.069 px; after blurred tips' energy is summed in a
//! fixed disc, 2026-11-27: 96.7 %, 99.32 %, 1 error, 0.069 px; measured
//! again after the tips' own lattice against an estimated scale,
//! 2026-12-05: 99.6 % (239/240), 99.68 %, 0 errors, 0.068 px, and the
//! floors raised to one image and 0.2 % of pins below that), not issue 12's targets (≥ 99.5 % verdicts,
//! ≥ 99.9 % pin statuses, no errors); docs/vision.md gives the figures
//! per factor and where the remaining wrong verdicts sit. A change that
//! lowers them fails; a change that raises them should raise the floors.

use pinsight::vision::synth_envelope::{EnvelopeCase, Rendered};
use pinsight::vision::{self, InspectOptions, View};
use rayon::prelude::*;

struct Outcome {
    view: View,
    error: bool,
    verdict_ok: bool,
    pins: usize,
    pins_wrong: usize,
    ok_errors: Vec<f64>,
}

fn run(seed: u64) -> Outcome {
    let case = EnvelopeCase::draw(seed);
    let r = case.render().expect("the generator renders every draw");
    let mut o = Outcome {
        view: case.factors.view,
        error: false,
        verdict_ok: false,
        pins: r.truth.pins.len(),
        pins_wrong: 0,
        ok_errors: Vec::new(),
    };
    match vision::inspect_gray(
        &case.recipe,
        &r.gray,
        r.info.clone(),
        &InspectOptions::default(),
    ) {
        Err(_) => {
            o.error = true;
            o.pins_wrong = o.pins;
        }
        Ok(ins) => {
            let c = r.compare(&case.factors, &ins);
            o.verdict_ok = c.verdict_ok;
            o.pins_wrong = c.status_mismatches.len();
            o.ok_errors = Rendered::ok_centre_errors(&c);
        }
    }
    o
}

fn pct(a: usize, b: usize) -> f64 {
    100.0 * a as f64 / b.max(1) as f64
}

#[test]
fn verdicts_hold_over_the_randomised_envelope() {
    let seeds = 200_000u64..200_240;
    let out: Vec<Outcome> = seeds.into_par_iter().map(run).collect();
    let n = out.len();
    let right = out.iter().filter(|o| o.verdict_ok).count();
    let errors = out.iter().filter(|o| o.error).count();
    let pins: usize = out.iter().map(|o| o.pins).sum();
    let pins_wrong: usize = out.iter().map(|o| o.pins_wrong).sum();
    let mut ok: Vec<f64> = out.iter().flat_map(|o| o.ok_errors.clone()).collect();
    ok.sort_by(|a, b| a.total_cmp(b));
    let median = ok[ok.len() / 2];
    let per_view = |v: View| {
        let s: Vec<&Outcome> = out.iter().filter(|o| o.view == v).collect();
        (s.iter().filter(|o| o.verdict_ok).count(), s.len())
    };
    let (top, side) = (per_view(View::Top), per_view(View::Side));
    eprintln!(
        "{n} images: verdicts right {right} ({:.1} %), errors {errors}, pin statuses right {:.2} %, \
         ok-pin centre error median {median:.3} px; top {:.1} % of {}, side {:.1} % of {}",
        pct(right, n),
        pct(pins - pins_wrong, pins),
        pct(top.0, top.1),
        top.1,
        pct(side.0, side.1),
        side.1
    );
    assert!(
        pct(right, n) >= 99.1,
        "connector verdicts right: {:.1} %",
        pct(right, n)
    );
    assert!(
        pct(pins - pins_wrong, pins) >= 99.45,
        "pin statuses right: {:.2} %",
        pct(pins - pins_wrong, pins)
    );
    assert!(
        errors == 0,
        "{errors} images inside the envelope ended as errors"
    );
    assert!(median <= 0.072, "ok-pin centre error median {median:.3} px");
}
