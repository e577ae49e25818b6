//! Every key the TUI understands, by context: the `?` help overlay lists
//! this table, and docs/tui.md copies it.

/// (context, keys, what they do).
pub const KEYS: &[(&str, &str, &str)] = &[
    ("everywhere", "?", "show / hide this help"),
    ("everywhere", "q  Ctrl-C", "quit"),
    ("everywhere", "Tab  Shift-Tab", "next / previous pane"),
    (
        "everywhere",
        "1 … 9  T",
        "Session Signals Overlay Model Study Vision Yield Methods Line, T Trend",
    ),
    (
        "everywhere",
        "o",
        "open files: type a path (log, image, recipe, parameters, folder), Enter",
    ),
    (
        "everywhere",
        "paste / drop",
        "a pasted or dropped path is opened",
    ),
    (
        "everywhere",
        "Esc  c",
        "cancel the running background work (Esc also closes help, prompts, edits)",
    ),
    ("everywhere", "j k  ↓ ↑", "next / previous row"),
    ("everywhere", "g G  Home End", "first / last row"),
    (
        "everywhere",
        "mouse",
        "click a tab; wheel scrolls (zooms on Signals)",
    ),
    (
        "live",
        "F",
        "follow the newest data on / off (tui --follow, demo --live)",
    ),
    (
        "live",
        "End  G",
        "resume following (Signals, Vision); looking back pauses it",
    ),
    ("Signals", "h l  ← →", "move the cursor"),
    ("Signals", "H L  Shift-← →", "pan half a window"),
    ("Signals", "+ -", "zoom in / out about the cursor"),
    (
        "Signals",
        "[ ]",
        "cursor to the previous / next cycle start",
    ),
    ("Signals", "Space", "show / hide the selected channel"),
    ("Signals", "0", "whole log"),
    ("Overlay", "n p  → ←", "next / previous cycle"),
    ("Overlay", "a", "envelope of all cycles"),
    (
        "Overlay",
        "C",
        "calibrate the log against the model (background, a few seconds)",
    ),
    (
        "Model",
        "Enter  e",
        "edit the selected value (Enter applies, Esc cancels)",
    ),
    ("Model", "r", "re-run the model"),
    ("Study", "r", "run the study in the background"),
    ("Study", "f", "next factor (clearance, speed, material)"),
    (
        "Study",
        "h l  ← →",
        "previous / next quantity (stroke, speed, acceleration, torque)",
    ),
    ("Vision", "n p  → ←", "next / previous image"),
    ("Vision", "r", "inspect the images again"),
    ("Methods", "j k", "choose the chart"),
    ("Methods", "r", "run the quick methods lab again"),
    (
        "Line",
        "j k  g G",
        "choose the cycle shown against its objects",
    ),
    ("Line", "r", "run the process monitor again"),
    ("Trend", "j k", "choose the head (rig) shown"),
    ("Trend", "r", "calibrate the logs and fit the trend again"),
];
