//! Bad or extreme parameters never panic: they are refused with a message
//! naming the key, or the run finishes, or it fails with a reported reason.

use pinsight::model::Params;
use pinsight::progress::Progress;
use pinsight::sim::{SimOptions, simulate};
use pinsight::solver::Method;
use proptest::prelude::*;

fn method_of(i: u8) -> Method {
    Method::ALL[usize::from(i) % 4]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, .. ProptestConfig::default() })]

    #[test]
    fn simulate_never_panics(
        // Mostly valid values (so that simulations run), sometimes invalid ones.
        c_mm in prop_oneof![1 => Just(0.0), 1 => -1.0f64..0.0, 6 => 1e-4f64..1.5],
        rpm in prop_oneof![1 => -10.0f64..0.0, 6 => 200.0f64..6000.0],
        rj_mm in prop_oneof![1 => -1.0f64..0.0, 6 => 0.5f64..12.0],
        l_mm in prop_oneof![1 => 1.0f64..9.0, 6 => 20.0f64..150.0],
        offset_mm in -4.0f64..4.0,
        m4 in prop_oneof![1 => -0.1f64..0.0, 6 => 0.005f64..1.0],
        ce in prop_oneof![1 => -0.5f64..0.0, 6 => 0.3f64..1.0],
        nu in prop_oneof![1 => 0.5f64..0.8, 6 => 0.0f64..0.45],
        material in 0usize..6,
        model in 0usize..5,
        method in 0u8..4,
        rtol_exp in 3i32..11,
        revs in prop_oneof![1 => -0.1f64..0.0, 6 => 0.02f64..0.15],
    ) {
        let mut p = Params::paper();
        let materials = ["alloy_steel", "stainless_steel", "aluminium", "copper", "tungsten_carbide", "mithril"];
        let models = ["lankarani_nikravesh", "flores", "hunt_crossley", "hertz", "springy"];
        let sets = vec![
            format!("clearance_mm={c_mm}"),
            format!("motor_rpm={rpm}"),
            format!("rj_mm={rj_mm}"),
            format!("l_mm={l_mm}"),
            format!("offset_mm={offset_mm}"),
            format!("m4_kg={m4}"),
            format!("restitution={ce}"),
            format!("material={}", materials[material]),
            format!("journal_nu={nu}"),
            format!("contact_model={}", models[model]),
        ];
        match p.apply_overrides(&sets) {
            Err(e) => {
                // Refused: the message names one of the keys.
                let msg = e.to_string();
                let keys = ["clearance_mm", "motor_rpm", "rj_mm", "l_mm", "offset_mm", "m4_kg", "restitution", "material", "journal_nu", "contact_model"];
                prop_assert!(keys.iter().any(|k| msg.contains(k)), "{msg}");
            }
            Ok(()) => {
                let o = SimOptions {
                    method: method_of(method),
                    rtol: 10f64.powi(-rtol_exp),
                    warmup: 0.0,
                    revs,
                    max_steps: 200_000,
                    grid_deg: Some(2.0),
                    ..SimOptions::default()
                };
                match simulate(&p, &o, &Progress::hidden()) {
                    Ok(r) => {
                        prop_assert!(r.summary.stroke_max_mm.is_finite());
                        prop_assert!(r.summary.n_impacts < 1_000_000);
                    }
                    Err(e) => prop_assert!(!e.to_string().is_empty()),
                }
            }
        }
    }
}
