//! The TUI's update loop driven by key, paste and mouse messages, with the
//! background jobs run in line: switching every pane, the help overlay,
//! editing a parameter (valid and invalid), opening a corrupt log and a
//! bad parameter file, cancelling work. Bad input shows an error in the
//! pane; the app never quits or panics on it.

use crossterm::event::{KeyCode, KeyEvent, KeyModifiers, MouseButton, MouseEvent, MouseEventKind};
use pinsight::panes::{PaneId, Session};
use pinsight::tui::app::{App, Msg};
use pinsight::tui::draw::ImageCache;
use pinsight::tui::theme::Theme;
use pinsight::tui::worker::{JobOutput, execute};
use pinsight::tui::{buffer_text, render_app};

fn key(c: KeyCode) -> Msg {
    Msg::Key(KeyEvent::new(c, KeyModifiers::NONE))
}

fn chars(app: &mut App, s: &str) {
    for c in s.chars() {
        app.update(key(KeyCode::Char(c)));
    }
}

/// Runs every queued job in line and delivers its output.
fn run_jobs(app: &mut App) {
    loop {
        let reqs = app.take_requests();
        if reqs.is_empty() {
            break;
        }
        for (id, req, progress) in reqs {
            let out = execute(req, &progress);
            app.update(Msg::JobDone(id, Box::new(out)));
        }
    }
}

fn screen(app: &App, w: u16, h: u16) -> String {
    let mut img = ImageCache::halfblocks();
    buffer_text(&render_app(app, w, h, &Theme::ansi16(), &mut img))
}

fn new_app() -> App {
    let mut app = App::new(Session::demo(), 120, 40);
    assert_eq!(app.running.len(), 1, "the model run is queued at start");
    run_jobs(&mut app);
    assert!(app.session.model.is_some());
    app
}

#[test]
fn every_pane_by_number_tab_and_mouse_and_help_lists_every_key() {
    let mut app = new_app();
    for (i, p) in PaneId::ALL.iter().enumerate() {
        // Panes 1–9 by their digit, the tenth (Trend) by T.
        let c = if i < 9 {
            char::from(b'1' + i as u8)
        } else {
            'T'
        };
        app.update(key(KeyCode::Char(c)));
        assert_eq!(app.pane, *p);
        // The Methods pane starts its lab when first shown.
        run_jobs(&mut app);
        let s = screen(&app, 120, 40);
        assert!(s.lines().next().unwrap().contains("1 Session"), "{s}");
    }
    assert!(
        app.session.methods.is_some(),
        "methods lab ran on first visit"
    );
    assert!(
        matches!(&app.session.monitor, Some(Ok(m)) if m.ok + m.nok == 20),
        "the process monitor ran on the Line pane's first visit"
    );
    // Both labs: the vision lab's localisers and, on every degradation
    // axis, the level where the verdicts break.
    let v = pinsight::panes::methods::view(&app.session, &app.ui);
    assert_eq!(v.localisers.len(), 3, "{:?}", v.localisers);
    for factor in ["noise", "blur", "contrast", "rotation"] {
        let b: Vec<_> = v.breakdown.iter().filter(|b| b.factor == factor).collect();
        assert!(!b.is_empty(), "{factor}: {:?}", v.breakdown);
        assert!(b.iter().all(|b| b.breaks_at.is_some()), "{factor}: {b:?}");
    }
    assert!(v.chart_titles.iter().any(|t| t == "Pipeline against blur"));
    app.update(key(KeyCode::Tab));
    assert_eq!(app.pane, PaneId::Session);
    app.update(key(KeyCode::BackTab));
    assert_eq!(app.pane, PaneId::Trend);
    // Click on the third tab.
    let tabs = pinsight::tui::draw::tabs(120);
    app.update(Msg::Mouse(MouseEvent {
        kind: MouseEventKind::Down(MouseButton::Left),
        column: tabs[2].2 + 1,
        row: 0,
        modifiers: KeyModifiers::NONE,
    }));
    assert_eq!(app.pane, PaneId::Overlay);
    app.update(key(KeyCode::Char('?')));
    assert!(app.help);
    let s = screen(&app, 120, 40);
    assert!(s.contains("Help — every key"), "{s}");
    // Every key of the table is reachable by scrolling.
    let mut seen = String::new();
    for _ in 0..pinsight::tui::keys::KEYS.len() {
        seen.push_str(&screen(&app, 80, 24));
        app.update(key(KeyCode::Char('j')));
    }
    for (_, keys, what) in pinsight::tui::keys::KEYS {
        let head: String = what.chars().take(20).collect();
        assert!(seen.contains(keys), "key `{keys}` not shown");
        assert!(seen.contains(&head), "`{what}` not shown");
    }
    app.update(key(KeyCode::Esc));
    assert!(!app.help);
    app.update(key(KeyCode::Char('q')));
    assert!(app.quit);
}

#[test]
fn editing_a_parameter_validates_and_reruns() {
    let mut app = new_app();
    app.update(key(KeyCode::Char('4')));
    // Select clearance_mm.
    let row = pinsight::panes::model::row_of_key("clearance_mm").unwrap();
    for _ in 0..row {
        app.update(key(KeyCode::Down));
    }
    app.update(key(KeyCode::Enter));
    assert_eq!(app.ui.model.editing.as_deref(), Some("0.1"));
    // An invalid value: the error shows in the pane, nothing changes, no re-run.
    app.update(Msg::Key(KeyEvent::new(
        KeyCode::Char('u'),
        KeyModifiers::CONTROL,
    )));
    chars(&mut app, "-0.3");
    app.update(key(KeyCode::Enter));
    assert!(!app.quit);
    assert!(app.requests.is_empty());
    let s = screen(&app, 120, 40);
    assert!(s.contains("invalid value for `clearance_mm`"), "{s}");
    assert!((app.session.params.clearance - 0.1e-3).abs() < 1e-15);
    // Text that is not a number.
    app.update(Msg::Key(KeyEvent::new(
        KeyCode::Char('u'),
        KeyModifiers::CONTROL,
    )));
    chars(&mut app, "wide");
    app.update(key(KeyCode::Enter));
    assert!(screen(&app, 80, 24).contains("clearance_mm"));
    // A valid value: accepted, re-run queued and its result shown.
    app.update(Msg::Key(KeyEvent::new(
        KeyCode::Char('u'),
        KeyModifiers::CONTROL,
    )));
    app.update(Msg::Paste("0.3".into()));
    app.update(key(KeyCode::Enter));
    assert!(app.ui.model.editing.is_none());
    assert!((app.session.params.clearance - 0.3e-3).abs() < 1e-15);
    assert_eq!(app.requests.len(), 1);
    let s = screen(&app, 120, 40);
    assert!(s.contains("re-run pending") || s.contains("model"), "{s}");
    run_jobs(&mut app);
    let m = app.session.model.as_ref().unwrap();
    assert!((m.params.clearance - 0.3e-3).abs() < 1e-15);
    assert!(screen(&app, 120, 40).contains("up to date"));
    // The level row takes a level name; a bad one is an error.
    app.update(key(KeyCode::Home));
    app.update(key(KeyCode::Down));
    app.update(key(KeyCode::Enter));
    app.update(Msg::Key(KeyEvent::new(
        KeyCode::Char('u'),
        KeyModifiers::CONTROL,
    )));
    chars(&mut app, "quantum");
    app.update(key(KeyCode::Enter));
    assert!(screen(&app, 120, 40).contains("invalid value for `level`"));
    app.update(key(KeyCode::Esc));
    assert!(app.ui.model.editing.is_none());
}

#[test]
fn corrupt_and_bad_files_show_errors_and_the_app_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("broken.mcap");
    std::fs::write(&log, b"\x89MCAP0\r\n\x00\x01garbage garbage garbage").unwrap();
    let params = dir.path().join("bad-params.toml");
    std::fs::write(&params, "clearance_mm = -5\n").unwrap();
    let good = dir.path().join("worn.toml");
    std::fs::write(&good, "preset = \"paper\"\nclearance_mm = 0.5\n").unwrap();
    let mut app = new_app();
    // Through the open prompt.
    app.update(key(KeyCode::Char('o')));
    chars(&mut app, &log.display().to_string());
    assert!(screen(&app, 120, 40).contains("path:"));
    app.update(key(KeyCode::Enter));
    run_jobs(&mut app);
    // Dropped on the terminal (a bracketed paste, quoted).
    app.update(Msg::Paste(format!("'{}'\n", params.display())));
    run_jobs(&mut app);
    let s = screen(&app, 120, 40);
    assert!(s.contains("Load errors (2)"), "{s}");
    assert!(s.contains("broken.mcap"), "{s}");
    assert!(s.contains("clearance_mm"), "{s}");
    assert!(!app.quit);
    assert!(
        (app.session.params.clearance - 0.1e-3).abs() < 1e-15,
        "bad file left the parameters alone"
    );
    // A good parameter file replaces the parameters and re-runs the model.
    app.update(Msg::Paste(good.display().to_string()));
    run_jobs(&mut app);
    assert!((app.session.params.clearance - 0.5e-3).abs() < 1e-15);
    assert!((app.session.model.as_ref().unwrap().params.clearance - 0.5e-3).abs() < 1e-15);
    // Text that is no path at all.
    app.update(Msg::Paste("   ".into()));
    assert!(app.message.as_ref().is_some_and(|m| m.1));
}

#[test]
fn background_work_shows_a_gauge_and_cancels() {
    let mut app = new_app();
    app.update(key(KeyCode::Char('5')));
    assert!(screen(&app, 120, 40).contains("press r to run"));
    app.update(key(KeyCode::Char('r')));
    assert_eq!(app.running.len(), 1);
    let s = screen(&app, 120, 40);
    assert!(s.lines().last().unwrap().contains("Esc/c cancels"), "{s}");
    let (id, req, progress) = app.take_requests().pop().unwrap();
    app.update(key(KeyCode::Esc));
    assert!(app.running.is_empty());
    assert!(progress.is_cancelled());
    // The cancelled study stops early and its result is ignored.
    let out = execute(req, &progress);
    match &out {
        JobOutput::Study(r) => assert!(r.cases.iter().all(|c| c.summary.is_none())),
        _ => panic!("expected a study"),
    }
    app.update(Msg::JobDone(id, Box::new(out)));
    assert!(app.session.study.is_none());
    assert!(screen(&app, 120, 40).contains("cancelled"));
}

#[test]
fn signals_keys_zoom_pan_toggle() {
    let mut app = new_app();
    app.update(key(KeyCode::Char('2')));
    // The demo's rig log: its channels, over its whole duration.
    let full = app.session.signal_set(0).unwrap().t_range();
    let first = app.session.signal_set(0).unwrap().channels[0].name.clone();
    app.update(key(KeyCode::Char('+')));
    app.update(key(KeyCode::Char('+')));
    let w = app.ui.signals.window.unwrap();
    let quarter = (full[1] - full[0]) / 4.0;
    assert!(
        ((w[1] - w[0]) - quarter).abs() < 1e-9 * quarter.max(1.0),
        "{w:?} vs {full:?}"
    );
    app.update(Msg::Key(KeyEvent::new(
        KeyCode::Char('L'),
        KeyModifiers::SHIFT,
    )));
    let w2 = app.ui.signals.window.unwrap();
    assert!(w2[0] > w[0]);
    app.update(key(KeyCode::Char(']')));
    app.update(key(KeyCode::Char(' ')));
    assert!(app.ui.signals.hidden.contains(&first));
    assert!(screen(&app, 80, 24).contains(&format!("[ ] {first}")));
    app.update(key(KeyCode::Char('0')));
    assert!(app.ui.signals.window.is_none());
}

#[test]
fn no_color_draws_without_colours_but_keeps_reverse_and_bold() {
    use ratatui::style::{Color, Modifier};
    let mut app = new_app();
    for pane in ['1', '2', '3', '4', '5'] {
        app.update(key(KeyCode::Char(pane)));
        let mut img = ImageCache::halfblocks();
        let buf = render_app(&app, 100, 30, &Theme::plain(), &mut img);
        for cell in buf.content() {
            assert!(matches!(cell.fg, Color::Reset), "{cell:?}");
            assert!(matches!(cell.bg, Color::Reset), "{cell:?}");
        }
        // The active tab is in reverse video.
        let tabs = pinsight::tui::draw::tabs(100);
        let i = (pane as u8 - b'1') as usize;
        let x = tabs[i].2 + 1;
        assert!(buf[(x, 0)].modifier.contains(Modifier::REVERSED));
    }
    // With 16 colours, only the 16 named colours (and Reset) appear.
    let mut img = ImageCache::halfblocks();
    let buf = render_app(&app, 100, 30, &Theme::ansi16(), &mut img);
    for cell in buf.content() {
        for c in [cell.fg, cell.bg] {
            assert!(!matches!(c, Color::Rgb(..) | Color::Indexed(_)), "{cell:?}");
        }
    }
}

#[test]
fn an_opened_image_is_drawn_with_half_blocks_and_next_previous_work() {
    let dir = tempfile::tempdir().unwrap();
    for (i, name) in ["a.png", "b.png"].iter().enumerate() {
        let img = image::RgbImage::from_fn(64, 48, |x, y| {
            if (x / 8 + y / 8 + i as u32).is_multiple_of(2) {
                image::Rgb([230, 230, 230])
            } else {
                image::Rgb([20, 20, 20])
            }
        });
        img.save(dir.path().join(name)).unwrap();
    }
    // A session without the demo's images.
    let mut app = App::new(Session::new("images only"), 120, 40);
    app.update(Msg::Paste(dir.path().display().to_string()));
    run_jobs(&mut app);
    assert_eq!(app.session.images.len(), 2);
    app.update(key(KeyCode::Char('6')));
    let s = screen(&app, 100, 30);
    assert!(s.contains("a.png (1/2)"), "{s}");
    assert!(
        s.contains('▀') || s.contains('▄'),
        "half-block image expected:\n{s}"
    );
    app.update(key(KeyCode::Char('n')));
    assert!(screen(&app, 100, 30).contains("b.png (2/2)"));
    app.update(key(KeyCode::Char('n')));
    assert!(screen(&app, 100, 30).contains("a.png (1/2)"));
    // Without colour the image is not drawn (half-blocks need colour).
    let mut img = ImageCache::halfblocks();
    let s = buffer_text(&render_app(&app, 100, 30, &Theme::plain(), &mut img));
    assert!(s.contains("image hidden (NO_COLOR)"), "{s}");
}

/// The demo's data panes: Vision inspects the image shown on the worker,
/// Yield runs the batch, Overlay compares the log with the model; every
/// number on screen comes from those runs. Ground truth of the four demo
/// images (fixtures/interop/images/*.json): one passes, three fail.
#[test]
fn vision_yield_and_overlay_run_on_the_worker_with_the_demo_data() {
    let mut app = new_app();
    app.update(key(KeyCode::Char('6')));
    assert_eq!(app.running.len(), 1, "showing Vision queues the inspection");
    assert!(screen(&app, 120, 40).contains("inspecting…"));
    run_jobs(&mut app);
    let s = screen(&app, 120, 40);
    assert!(s.contains("verdict: FAIL"), "{s}");
    assert!(
        s.contains("HDR-2x10-2.54 (recognised among 4 recipes"),
        "{s}"
    );
    assert!(s.contains("Pins (20)"), "{s}");
    // Next image: round pins, a pass in the ground truth.
    app.update(key(KeyCode::Char('n')));
    run_jobs(&mut app);
    let s = screen(&app, 120, 40);
    assert!(s.contains("r1x8-00.jpg (2/4)"), "{s}");
    assert!(s.contains("verdict: PASS"), "{s}");
    // Yield: the batch over the four images.
    app.update(key(KeyCode::Char('7')));
    assert!(app.running.iter().any(|r| r.label.contains("yield")));
    run_jobs(&mut app);
    let y = &app.session.yields.as_ref().unwrap().report;
    assert_eq!((y.passed, y.failed, y.errors), (1, 3, 0));
    let s = screen(&app, 120, 40);
    assert!(s.contains("yield 25.0 %"), "{s}");
    assert!(s.contains("Wilson"), "{s}");
    // Overlay: the log's 20 cycles against the predicted ensemble.
    app.update(key(KeyCode::Char('3')));
    assert!(app.running.iter().any(|r| r.label.contains("overlay")));
    run_jobs(&mut app);
    let s = screen(&app, 120, 40);
    assert!(s.contains("envelope of 20 cycles"), "{s}");
    assert!(s.contains("stroke residual"), "{s}");
    app.update(key(KeyCode::Char('n')));
    assert!(screen(&app, 120, 40).contains("stroke (mm) — cycle 0"));
}

/// Cancelling the yield keeps partial work out and does not restart it
/// until asked (r).
#[test]
fn a_cancelled_yield_is_not_restarted_until_asked() {
    let mut app = new_app();
    app.update(key(KeyCode::Char('7')));
    assert_eq!(app.running.len(), 1);
    let (_, _, progress) = app.requests[0].clone();
    app.update(key(KeyCode::Esc));
    assert!(progress.is_cancelled());
    assert!(app.running.is_empty());
    let _ = app.take_requests();
    app.update(key(KeyCode::Char('j')));
    assert!(app.running.is_empty(), "not restarted by itself");
    app.update(key(KeyCode::Char('r')));
    assert_eq!(app.running.len(), 1);
    run_jobs(&mut app);
    assert!(app.session.yields.is_some());
}

/// The Overlay pane calibrates its log on `C` (a background job with a
/// gauge, never by itself): the pane then shows the fitted clearance ±
/// U95, standoff, lags and the residual before → after, from the same job
/// as `pinsight calibrate`.
#[test]
fn the_overlay_pane_calibrates_its_log_on_capital_c() {
    let mut app = new_app();
    app.update(key(KeyCode::Char('3')));
    run_jobs(&mut app);
    assert!(app.session.calibrations.is_empty(), "not run by itself");
    assert!(!screen(&app, 120, 40).contains("Calibration (C)"));
    app.update(key(KeyCode::Char('C')));
    assert!(
        app.running.iter().any(|r| r.label.contains("calibrating")),
        "{:?}",
        app.running.iter().map(|r| &r.label).collect::<Vec<_>>()
    );
    run_jobs(&mut app);
    let run = app.session.calibration_of(0).expect("calibrated");
    let report = run.report.as_ref().expect("the demo log calibrates");
    let (log, cycles) = app.session.logs[0].rig.clone().unwrap();
    let direct = pinsight::engine::calibrate::run_calibration(
        0,
        &log,
        &cycles,
        &pinsight::progress::Progress::hidden(),
    );
    let direct = direct.report.unwrap();
    assert_eq!(
        serde_json::to_value(&**report).unwrap(),
        serde_json::to_value(&*direct).unwrap()
    );
    let view = pinsight::panes::overlay::view(&app.session, &app.ui);
    let c = view.calibration.expect("the pane shows the calibration");
    let clearance = &report.estimates[0];
    assert_eq!(clearance.name, "clearance");
    assert_eq!(c.clearance_mm, Some(clearance.value));
    assert_eq!(c.clearance_u95_mm, Some(clearance.u95));
    let s = screen(&app, 120, 40);
    assert!(s.contains("Calibration (C)"), "{s}");
    assert!(s.contains("clearance:"), "{s}");
    assert!(s.contains("stroke mean RMS:"), "{s}");
}

/// `tui --follow` with a config file: the `[alarms]` rules of the config
/// are the ones the live line is judged by, and a raised alarm reaches the
/// status line drawn by the TUI's own loop. The log runs at 1800 rpm; the
/// config's `speed_off` rule holds a 1000 rpm set-point, so it must raise;
/// the default rules (set-point from the log's metadata) must not.
#[test]
fn tui_follow_applies_the_config_alarm_rules_and_shows_them() {
    use pinsight::tui::event_loop::{QuitWhen, drive_headless};
    use std::cell::Cell;
    use std::rc::Rc;
    use std::time::{Duration, Instant};

    let log = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures/logs/synth-1800-ripple-dropouts-blocks.mcap");
    // Follows the finished log until every cycle is in (or 60 s); returns
    // the alarms raised and the last status line drawn.
    let follow = |config_text: &str| -> (Vec<String>, String) {
        let (config, findings) = pinsight::tui::config::Config::parse(config_text, "test.toml");
        assert!(findings.is_empty(), "{findings:?}");
        let inputs = pinsight::cli::watch::inputs(
            std::slice::from_ref(&log),
            &[],
            None,
            0,
            config.follow_settings(),
            None,
            &pinsight::cli::common::LogReadArgs {
                channels: None,
                meta: Vec::new(),
            },
        )
        .unwrap();
        let mut session = Session::new("live");
        let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
        let (rx, rules) = pinsight::tui::start_follow(&mut session, inputs, stop.clone()).unwrap();
        let mut app = App::new(session, 100, 30);
        let done = Rc::new(Cell::new(false));
        let mut raised: Vec<String> = Vec::new();
        let deadline = Instant::now() + Duration::from_secs(60);
        let seen = done.clone();
        let mut events = QuitWhen(move || seen.get() || Instant::now() >= deadline);
        let last = drive_headless(
            &mut app,
            (100, 30),
            &mut events,
            Some((&rx, &rules)),
            &mut |app: &App| {
                let Some(l) = app.session.live.as_ref() else {
                    return;
                };
                for a in &l.active_alarms {
                    if !raised.iter().any(|r| r == a) {
                        raised.push(a.to_string());
                    }
                }
                // Every file finished: the whole log is in.
                if !l.files.is_empty()
                    && l.files
                        .iter()
                        .all(|f| f.1 == pinsight::live::events::FileState::Finished)
                {
                    done.set(true);
                }
            },
        )
        .unwrap();
        stop.store(true, std::sync::atomic::Ordering::Relaxed);
        let status = buffer_text(&last)
            .lines()
            .find(|l| l.contains("cycles ·"))
            .unwrap_or_default()
            .to_string();
        assert!(done.get(), "the log was not followed to its end in 60 s");
        (raised, status)
    };

    let (raised, status) = follow(
        "[[alarms.rule]]\nkind = \"speed_off\"\ntolerance = 0.02\nconsecutive = 3\nsetpoint_rpm = 1000.0\n",
    );
    assert!(
        raised.iter().any(|r| r == "speed_off"),
        "the config's speed_off rule did not raise: {raised:?}"
    );
    assert!(
        status.contains("ALARM") && status.contains("speed_off"),
        "{status}"
    );

    let (raised, _) = follow("");
    assert!(
        !raised.iter().any(|r| r == "speed_off"),
        "the default rules raised speed_off at the log's own set-point: {raised:?}"
    );
}
