//! Snapshot tests of every pane drawn by the TUI's drawing code into
//! ratatui's TestBackend, at 80×24 and 120×40. The snapshot files in
//! tests/snapshots/ are reviewed by eye: they are what a technician sees.

mod common;

use pinsight::batch::render_text;
use pinsight::panes::{PaneId, PaneState};
use std::sync::OnceLock;

fn session() -> &'static pinsight::panes::Session {
    static S: OnceLock<pinsight::panes::Session> = OnceLock::new();
    S.get_or_init(common::full_session_with_methods)
}

fn shot(pane: PaneId, w: u16, h: u16) -> String {
    let ui = PaneState::new(w, h);
    let text = render_text(session(), pane, &ui);
    assert_eq!(text.lines().count(), h as usize);
    text
}

/// Vision on every demo image (top views of three parts, a side view).
#[test]
fn vision_every_demo_image() {
    let mut s = session().clone();
    for i in 0..s.images.len() {
        s.inspect_now(i);
    }
    for i in 1..s.images.len() {
        let mut ui = PaneState::new(120, 40);
        ui.set_option("vision.image", &i.to_string()).unwrap();
        insta::assert_snapshot!(
            format!("vision_image_{i}"),
            render_text(&s, PaneId::Vision, &ui)
        );
    }
}

/// Overlay of one cycle (not the envelope).
#[test]
fn overlay_one_cycle() {
    let mut ui = PaneState::new(120, 40);
    ui.set_option("overlay.cycle", "3").unwrap();
    insta::assert_snapshot!(render_text(session(), PaneId::Overlay, &ui));
}

macro_rules! pane_snapshots {
    ($($name:ident => $pane:expr),* $(,)?) => {
        $(
            #[test]
            fn $name() {
                insta::assert_snapshot!(concat!(stringify!($name), "_80x24"), shot($pane, 80, 24));
                insta::assert_snapshot!(concat!(stringify!($name), "_120x40"), shot($pane, 120, 40));
            }
        )*
    };
}

pane_snapshots! {
    session_pane => PaneId::Session,
    signals_pane => PaneId::Signals,
    overlay_pane => PaneId::Overlay,
    model_pane => PaneId::Model,
    study_pane => PaneId::Study,
    vision_pane => PaneId::Vision,
    yield_pane => PaneId::Yield,
    methods_pane => PaneId::Methods,
}

#[test]
fn study_by_speed_and_torque() {
    let mut ui = PaneState::new(120, 40);
    ui.set_option("study.factor", "speed").unwrap();
    ui.set_option("study.quantity", "torque").unwrap();
    insta::assert_snapshot!(render_text(session(), PaneId::Study, &ui));
}

#[test]
fn signals_zoomed_with_a_hidden_channel() {
    let mut ui = PaneState::new(120, 40);
    ui.set_option("signals.t0", "0.4").unwrap();
    ui.set_option("signals.t1", "0.5").unwrap();
    ui.set_option("signals.cursor", "0.45").unwrap();
    ui.set_option("signals.hide", "speed").unwrap();
    let text = render_text(session(), PaneId::Signals, &ui);
    assert!(text.contains("[ ] speed"), "{text}");
    assert!(text.contains("0.400–0.500 s"), "{text}");
    insta::assert_snapshot!(text);
}
