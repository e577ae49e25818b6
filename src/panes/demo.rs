//! The embedded demo session: what `pinsight` (no arguments) opens, so every
//! pane shows real data on first start.
//!
//! Embedded (≈ 380 kB in the binary, all copies of the interop fixtures):
//! - the rig log `run-1200-blocks.mcap` (248 kB: 20 cycles at 1200 rpm, force
//!   and displacement as blocks; written from the reference clearance
//!   simulation, so the Overlay pane's comparison is meaningful; the small
//!   `fixtures/logs/synth-*` logs come from the ideal mechanism instead);
//! - the process recipe of the log's part (`fixtures/process/`), its
//!   envelope learned on the log's first cycles, for the Line pane;
//! - four connector images of four parts (two top-view headers, a round-pin
//!   header, a side view) and their recipes; the images name no part number,
//!   so the vision library recognises each part among the recipes.
//!
//! Building it decodes the log and the images (a few ms, see the first-frame
//! benchmark in `benches/tui.rs`); the model run, the inspections, the yield
//! and the overlay run on the worker after the first frame.

use super::session::Session;
use crate::engine::entries::ImageSource;
use crate::engine::load::{load_image_bytes, load_log_bytes, load_toml_text};
use std::sync::Arc;

/// The demo rig log.
pub const LOG: (&str, &[u8]) = (
    "demo/run-1200-blocks.mcap",
    include_bytes!("../../fixtures/interop/logs/run-1200-blocks.mcap"),
);

/// The demo connector images (name, bytes).
pub const IMAGES: [(&str, &[u8]); 4] = [
    (
        "demo/h2x10-01.jpg",
        include_bytes!("../../fixtures/interop/images/h2x10-01.jpg"),
    ),
    (
        "demo/r1x8-00.jpg",
        include_bytes!("../../fixtures/interop/images/r1x8-00.jpg"),
    ),
    (
        "demo/h2x8a-03.jpg",
        include_bytes!("../../fixtures/interop/images/h2x8a-03.jpg"),
    ),
    (
        "demo/s1x10-05.jpg",
        include_bytes!("../../fixtures/interop/images/s1x10-05.jpg"),
    ),
];

/// The recipes of the demo images (name, text).
pub const RECIPES: [(&str, &str); 4] = [
    (
        "demo/hdr-2x10.toml",
        include_str!("../../fixtures/interop/images/hdr-2x10.toml"),
    ),
    (
        "demo/rnd-1x8.toml",
        include_str!("../../fixtures/interop/images/rnd-1x8.toml"),
    ),
    (
        "demo/hdr-2x8-auto.toml",
        include_str!("../../fixtures/interop/images/hdr-2x8-auto.toml"),
    ),
    (
        "demo/side-1x10.toml",
        include_str!("../../fixtures/interop/images/side-1x10.toml"),
    ),
];

/// The process recipe of the demo log's part (its envelope learned on the
/// log's first 10 cycles), so the Line pane shows the monitor.
pub const PROCESS_RECIPE: (&str, &str) = (
    "demo/hdr-2x10.process.toml",
    include_str!("../../fixtures/process/demo-hdr-2x10.process.toml"),
);

impl Session {
    /// The embedded demo session (see [`session`]).
    pub fn demo() -> Self {
        session()
    }
}

/// The demo session (nothing run yet: the TUI runs the model and the
/// analyses on its worker, batch mode and `render` run them in line).
pub fn session() -> Session {
    let mut s = Session::new(
        "demo (embedded): the paper pin-insertion head, a rig log and four connectors",
    );
    s.absorb(load_log_bytes(LOG.0, LOG.1));
    for (name, text) in RECIPES {
        s.absorb(vec![load_toml_text(name, text)]);
    }
    s.absorb(vec![load_toml_text(PROCESS_RECIPE.0, PROCESS_RECIPE.1)]);
    for (name, bytes) in IMAGES {
        s.absorb(vec![load_image_bytes(
            name,
            ImageSource::Bytes(Arc::new(bytes.to_vec())),
            bytes,
        )]);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_demo_holds_a_log_recipes_and_images_without_errors() {
        let s = session();
        assert!(s.load_errors().is_empty(), "{:?}", s.load_errors());
        assert_eq!(s.logs.len(), 1);
        assert_eq!(s.recipes.len(), RECIPES.len());
        assert_eq!(s.process_recipes.len(), 1);
        assert_eq!(s.images.len(), IMAGES.len());
        // The log's truth file: 20 complete cycles.
        let (_, cycles) = s.logs[0].rig.as_ref().unwrap();
        assert_eq!(cycles.cycles.len(), 20);
    }
}
