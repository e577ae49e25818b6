//! A faulty line for tests and demos (issue 16's generator mode): a rig log
//! whose cycles carry insertion faults ([`crate::rig::synth::faults`]) and,
//! on the camera topic, a side-view photograph of every connector those
//! cycles made ([`crate::vision::synth`]), with the truth of both.
//!
//! The two generators are joined here, above both (the rig generator knows
//! nothing of images, the vision generator nothing of cycles): one draw per
//! cycle decides the fault, its force signature and what the camera sees.
//!
//! | fault | the connector in the side view |
//! |---|---|
//! | `missing_pin` | one pin absent |
//! | `too_deep` | every pin stands Δ lower (height − Δ) |
//! | `not_fully_inserted` | every pin stands Δ higher |
//! | `out_of_position` | one pin bent sideways by the drawn shift, the others by up to half of it |
//! | (none) | heights within the part-to-part seating jitter |
//!
//! Independently of the process, a connector may carry debris (a vision
//! fault the force curve cannot see): the disagreements the connector's
//! story is meant to list.

use super::story::Confusion;
use crate::rig::synth::faults::{CycleDraw, FaultRates, FaultTruth, InsertionFault, draw_cycles};
use crate::rig::synth::{IdealTruth, SynthChannel, SynthConfig, SynthLog, SynthMessage, generate};
use crate::vision::result::Verdict;
use crate::vision::synth::{Rng as SceneRng, Scene, SceneExtra};
use crate::vision::{GrayData, Recipe};
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// What to generate.
#[derive(Debug, Clone)]
pub struct FaultyLineConfig {
    /// The run (speed, sensors, length, seed, metadata: `part_number` is set
    /// to the vision recipe's).
    pub rig: SynthConfig,
    pub rates: FaultRates,
    /// The side-view recipe of the connector (every cycle photographs one).
    pub recipe: Recipe,
    /// Probability of debris on a connector, independent of the process.
    pub debris_rate: f64,
    /// Photograph the connectors (false: the log has no camera topic).
    pub images: bool,
}

/// One connector's truth.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConnectorTruth {
    pub cycle: u64,
    pub fault: Option<InsertionFault>,
    /// Whether the process should be judged NOK (a fault was drawn).
    pub process_nok: bool,
    /// The vision verdict of the photograph (the renderer's exact truth);
    /// None without images.
    pub vision: Option<Verdict>,
    pub debris: bool,
    pub draw: CycleDraw,
    /// The photograph's pins as painted (height, offset), when images were made.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub pins: Vec<crate::vision::truth::TruthPin>,
}

/// The truth of a faulty line: per connector, and the confusion table
/// (process NOK × vision fail) a correct report must show.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LineTruth {
    pub part_number: String,
    pub connectors: Vec<ConnectorTruth>,
    pub confusion: Confusion,
}

/// The foxglove.CompressedImage JSON schema of the camera topic.
pub const IMAGE_SCHEMA: &str = r#"{"title": "foxglove.CompressedImage", "type": "object", "properties": {"timestamp": {"type": "object", "properties": {"sec": {"type": "integer"}, "nsec": {"type": "integer"}}}, "frame_id": {"type": "string"}, "format": {"type": "string"}, "data": {"type": "string", "contentEncoding": "base64"}}}"#;

/// Renders the connector of one cycle.
pub fn connector_scene(recipe: &Recipe, d: &CycleDraw, debris: bool, seed: u64) -> Scene {
    let mut rng = SceneRng::new(seed);
    let mut sc = Scene::nominal(recipe, recipe.mm_per_px.unwrap_or(0.025));
    sc.seed = seed;
    sc.rotation_deg = rng.range(-1.0, 1.0);
    sc.centre_px.0 += rng.range(-10.0, 10.0);
    sc.blur_px = rng.range(0.3, 1.2);
    sc.noise_dn = rng.range(1.0, 4.0);
    sc.contrast = rng.range(0.7, 1.0);
    let tol = recipe.tolerance.position_mm;
    for p in &mut sc.pins {
        // The gang's seating: deeper seated pins stand lower.
        p.height_mm -= d.depth_dev_mm;
        p.offset_mm = (0.1 * tol * rng.normal(), 0.0);
    }
    match d.fault {
        Some(InsertionFault::MissingPin) => {
            let k = (rng.uniform() * sc.pins.len() as f64) as usize % sc.pins.len().max(1);
            if let Some(p) = sc.pins.get_mut(k) {
                p.present = false;
            }
        }
        Some(InsertionFault::OutOfPosition) => {
            // Landing on the housing bends the pins: one by the whole shift,
            // the others by up to half of it.
            let n = sc.pins.len().max(1);
            let full = (rng.uniform() * n as f64) as usize % n;
            for (j, p) in sc.pins.iter_mut().enumerate() {
                let f = if j == full { 1.0 } else { rng.range(0.0, 0.5) };
                let s = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
                p.offset_mm.0 = s * f * d.shift_mm.abs();
            }
        }
        _ => {}
    }
    if debris {
        // Dust between two pins (not on a pin's silhouette, which would hide it).
        let gaps = recipe.cols.max(2) - 1;
        let j = (rng.uniform() * gaps as f64) as u32 % gaps;
        let (u, _) = recipe.nominal_uv_mm(0, j);
        sc.extras.push(SceneExtra {
            u_mm: u + 0.5 * recipe.pitch_mm[0],
            v_mm: -rng.range(0.5, 1.5),
            r_mm: rng.range(0.17, 0.25),
            opacity: rng.range(0.75, 0.95),
        });
    }
    sc
}

/// A rendered image as PNG bytes.
pub fn png_of(g: &crate::vision::Gray) -> Vec<u8> {
    let img = match &g.data {
        GrayData::U8(d) => image::DynamicImage::ImageLuma8(
            image::GrayImage::from_raw(g.width, g.height, d.clone()).unwrap_or_default(),
        ),
        GrayData::U16(d) => image::DynamicImage::ImageLuma16(
            image::ImageBuffer::from_raw(g.width, g.height, d.clone()).unwrap_or_default(),
        ),
    };
    let mut out = std::io::Cursor::new(Vec::new());
    // Encoding a well-formed in-memory image into a Vec cannot fail.
    let _ = img.write_to(&mut out, image::ImageFormat::Png);
    out.into_inner()
}

/// Generates the log (in memory) and its truth.
pub fn faulty_line(cfg: &FaultyLineConfig) -> (SynthLog, LineTruth) {
    let mut rig = cfg.rig.clone();
    let mut meta = rig.rig_metadata();
    meta.insert("part_number".into(), cfg.recipe.part_number.clone());
    rig.metadata = Some(meta);
    let tdcs = rig.tdc_times();
    let n_marks = tdcs.len();
    let draws = draw_cycles(n_marks, &cfg.rates, rig.seed);
    let ideal = IdealTruth::from_params(&crate::model::Params::paper());
    let tdc = ideal.geometry.tdc_angle();
    let first_revolution = tdcs.first().map_or(0, |&(tau, _)| {
        let (th, _) = rig.crank(tau);
        ((th - tdc) / TAU).round() as i64
    });
    let truth = FaultTruth {
        ideal,
        first_revolution,
        pins: cfg.rates.pins,
        cycles: draws.clone(),
    };
    let mut log = generate(&rig, &truth);
    let mut debris_rng = crate::rng::SplitMix64::<0xDEB0_1500_0000_0016>::new(rig.seed);
    let mut connectors = Vec::new();
    let mut confusion = Confusion::default();
    let cam = log.channels.len();
    if cfg.images {
        log.channels.push(SynthChannel {
            topic: crate::rig::images::CAMERA_TOPIC.into(),
            schema_name: "foxglove.CompressedImage".into(),
            schema_encoding: "jsonschema".into(),
            schema: IMAGE_SCHEMA.into(),
            message_encoding: "json".into(),
        });
    }
    // A connector per complete cycle: from one mark to the next.
    for (k, w) in tdcs.windows(2).enumerate() {
        let d = draws[k];
        let debris = debris_rng.uniform() < cfg.debris_rate;
        let mut pins = Vec::new();
        let vision = if cfg.images {
            let sc = connector_scene(&cfg.recipe, &d, debris, rig.seed ^ ((k as u64 + 1) << 20));
            let (g, t) = sc.render();
            // Photographed 5 ms after the cycle ends.
            let lt = rig.start_ns + ((w[1].0 + 0.005) * 1e9).round() as u64;
            let data =
                base64::Engine::encode(&base64::engine::general_purpose::STANDARD, png_of(&g));
            let msg = serde_json::json!({
                "timestamp": {"sec": lt / 1_000_000_000, "nsec": lt % 1_000_000_000},
                "frame_id": format!("cycle-{k}"),
                "format": "png",
                "data": data,
            });
            log.messages.push(SynthMessage {
                channel: cam,
                log_time: lt,
                publish_time: lt + 8_000_000,
                data: msg.to_string().into_bytes(),
            });
            pins = t.pins;
            Some(t.verdict)
        } else {
            None
        };
        let process_nok = d.fault.is_some();
        confusion.add(process_nok, vision == Some(Verdict::Fail));
        connectors.push(ConnectorTruth {
            cycle: k as u64,
            fault: d.fault,
            process_nok,
            vision,
            debris,
            draw: d,
            pins,
        });
    }
    log.messages.sort_by_key(|m| m.log_time);
    let truth = LineTruth {
        part_number: cfg.recipe.part_number.clone(),
        connectors,
        confusion,
    };
    (log, truth)
}
