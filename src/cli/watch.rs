//! `pinsight watch PATHS [--json-lines]`: follows rig logs while they are
//! written and folders where images arrive, headless: one line per new
//! cycle, image, alarm, finding or file state (JSON with `--json-lines`,
//! for piping into other tools), and a summary at the end.

use crate::live::events::LiveEvent;
use crate::live::wake::Wake;
use crate::live::{AlarmRules, FollowConfig, FollowInputs, Follower, parse_duration};
use crate::process::ProcessRecipe;
use crate::vision::batch::RecipeBook;
use anyhow::anyhow;
use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Logs (.mcap, followed while written; a missing one is waited for) and folders (images, new logs).
    #[arg(required = true)]
    pub paths: Vec<PathBuf>,
    /// One JSON object per line: {"event": "cycle" | "image" | "alarm" | "finding" | "file" | "summary", …}.
    #[arg(long)]
    pub json_lines: bool,
    /// Poll every DURATION instead of using file-system events (network shares), e.g. 2s.
    #[arg(long, value_name = "DURATION")]
    pub poll: Option<String>,
    /// Vision recipe(s) for the images (file or folder of .toml).
    #[arg(long = "recipe", short = 'r')]
    pub recipes: Vec<PathBuf>,
    /// Process recipe: every cycle judged OK / NOK.
    #[arg(long)]
    pub process: Option<PathBuf>,
    /// Learn the process recipe's envelopes on the first N good cycles.
    #[arg(long, default_value_t = 0)]
    pub learn: usize,
    /// TOML with [follow] and [alarms] sections (see docs/live.md).
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Ring the terminal bell (on stderr) when an alarm is raised.
    #[arg(long)]
    pub bell: bool,
    /// Send an OSC 9 notification (on stderr) when an alarm is raised.
    #[arg(long)]
    pub osc9: bool,
    /// Exit when every followed log is finished (its footer written).
    #[arg(long)]
    pub until_finished: bool,
    /// Stop after this much wall time (e.g. 8h).
    #[arg(long, value_name = "DURATION")]
    pub max_time: Option<String>,
    #[command(flatten)]
    pub log: super::common::LogReadArgs,
}

/// Reads the follow defaults and alarm rules of a config file.
/// `path` (`--config FILE`), else the technician's config file
/// ([`crate::tui::config::default_path`]) when it exists; its other
/// sections (keys, theme, mouse) are the TUI's and ignored here. Headless,
/// a bad `[follow]` or `[alarms]` is an error naming the file.
pub fn read_config(path: Option<&PathBuf>) -> anyhow::Result<(FollowConfig, AlarmRules)> {
    let default = crate::tui::config::default_path().filter(|p| p.is_file());
    let Some(p) = path.or(default.as_ref()) else {
        return Ok((FollowConfig::default(), AlarmRules::default()));
    };
    let text = crate::input::read_text(p).map_err(|e| anyhow!("{}: {e}", p.display()))?;
    let table: toml::Table = text
        .parse()
        .map_err(|e: toml::de::Error| anyhow!("{}: {e}", p.display()))?;
    let follow = match table.get("follow") {
        Some(_) => {
            FollowConfig::from_toml(&text).map_err(|e| anyhow!("{} [follow]: {e}", p.display()))?
        }
        None => FollowConfig::default(),
    };
    let alarms = match table.get("alarms") {
        Some(_) => {
            AlarmRules::from_toml(&text).map_err(|e| anyhow!("{} [alarms]: {e}", p.display()))?
        }
        None => AlarmRules::default(),
    };
    Ok((follow, alarms))
}

/// What `watch`, `tui --follow` and `demo --live` follow.
pub fn inputs(
    paths: &[PathBuf],
    recipes: &[PathBuf],
    process: Option<&PathBuf>,
    learn: usize,
    (mut cfg, alarms): (FollowConfig, AlarmRules),
    poll: Option<&str>,
    log: &super::common::LogReadArgs,
) -> anyhow::Result<FollowInputs> {
    if let Some(p) = poll {
        cfg.poll_s = parse_duration(p)
            .map_err(|e| anyhow!("--poll: {e}"))?
            .max(0.01);
        cfg.notify = false;
    }
    let lo = log.load_options()?;
    let process = match process {
        None => None,
        Some(p) => Some(ProcessRecipe::load(p).map_err(|e| anyhow!("{e}"))?),
    };
    let recipes = if recipes.is_empty() {
        // The simulated line's connector, so `watch` on `rig-sim` output judges it.
        match crate::vision::Recipe::from_toml_str(crate::live::sim::RECIPE, "side-1x6 (embedded)")
        {
            Ok(r) => RecipeBook::new(vec![r]),
            Err(_) => RecipeBook::default(),
        }
    } else {
        RecipeBook::load(recipes)
    };
    Ok(FollowInputs {
        paths: paths.to_vec(),
        recipes,
        process,
        learn,
        channel_map: lo.channel_map,
        cycle_options: crate::rig::cycles::CycleOptions::default(),
        meta_overrides: lo.meta_overrides,
        config: cfg,
        alarms,
    })
}

fn human(e: &LiveEvent) -> String {
    match e {
        LiveEvent::Cycle(c) => format!(
            "cycle {:>6} {}  {:.1} rpm  depth {:.3} mm  peak {:.1} N  stroke dev {:.4} mm{}",
            c.index,
            c.file,
            c.motor_rpm,
            c.depth_mm,
            c.peak_force_n,
            c.stroke_dev_rms_mm,
            c.status
                .map(|s| format!(
                    "  {}{}",
                    s.to_uppercase(),
                    if c.reasons.is_empty() {
                        String::new()
                    } else {
                        format!(" ({})", c.reasons.join("; "))
                    }
                ))
                .unwrap_or_default()
        ),
        LiveEvent::Image(i) => format!(
            "image {:?} {}{}{}",
            i.status,
            i.name,
            i.cycle.map(|c| format!(" (cycle {c})")).unwrap_or_default(),
            i.error
                .as_ref()
                .map(|e| format!(": {e}"))
                .unwrap_or_default()
        ),
        LiveEvent::Alarm(a) => format!(
            "ALARM {} {}: {}",
            if a.raised { "RAISED" } else { "cleared" },
            a.rule,
            a.message
        ),
        LiveEvent::Finding(f) => format!("finding [{:?}] {}", f.severity, f.message),
        LiveEvent::File(f) => format!(
            "file {} {:?} ({} bytes, {} cycles)",
            f.path, f.state, f.bytes, f.cycles
        ),
    }
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let mut inp = inputs(
        &args.paths,
        &args.recipes,
        args.process.as_ref(),
        args.learn,
        read_config(args.config.as_ref())?,
        args.poll.as_deref(),
        &args.log,
    )?;
    inp.alarms.bell |= args.bell;
    inp.alarms.osc9 |= args.osc9;
    let rules = inp.alarms.clone();
    let max = match &args.max_time {
        Some(m) => Some(parse_duration(m).map_err(|e| anyhow!("--max-time: {e}"))?),
        None => None,
    };
    let cfg = inp.config.clone();
    let mut follower = Follower::new(inp);
    let mut wake = Wake::new(
        &follower.watch_paths(),
        cfg.notify,
        cfg.poll_s,
        cfg.debounce_ms,
    );
    let stop = Arc::new(AtomicBool::new(false));
    crate::progress::stop_on_signals(&stop)?;
    if let Some(n) = &wake.note
        && !args.json_lines
    {
        eprintln!("watch: {n}");
    }
    let started = Instant::now();
    let mut changed = None;
    let emit = |events: &[LiveEvent]| -> anyhow::Result<()> {
        let mut text = String::new();
        for e in events {
            if args.json_lines {
                text.push_str(&serde_json::to_string(e)?);
            } else {
                text.push_str(&human(e));
            }
            text.push('\n');
            if let LiveEvent::Alarm(a) = e
                && a.raised
            {
                let n = rules.notification(&format!("{}: {}", a.rule, a.message));
                if !n.is_empty() {
                    let mut err = std::io::stderr();
                    let _ = err.write_all(n.as_bytes());
                    let _ = err.flush();
                }
            }
        }
        if !text.is_empty() {
            super::common::out(&text)?;
        }
        Ok(())
    };
    let out_of_time =
        || stop.load(Ordering::Relaxed) || max.is_some_and(|m| started.elapsed().as_secs_f64() > m);
    loop {
        let batch = follower.poll(changed.as_deref());
        emit(&batch.events)?;
        if out_of_time() {
            emit(&follower.stop().events)?;
            break;
        }
        if args.until_finished && follower.all_finished() {
            // Images written just before the footer: one last look, and on
            // while the folder or the queue holds more than one poll
            // inspects (64): with the queue empty when the log finished,
            // a single look read 64 of the 149 images written meanwhile.
            std::thread::sleep(std::time::Duration::from_millis(
                crate::live::folder::SETTLE_MS + 50,
            ));
            loop {
                emit(&follower.poll(None).events)?;
                if !follower.behind() || out_of_time() {
                    break;
                }
            }
            break;
        }
        changed = wake.next(follower.behind()).changed;
    }
    let s = follower.summary();
    if args.json_lines {
        let mut v = serde_json::to_value(&s)?;
        if let Some(o) = v.as_object_mut() {
            o.insert("event".into(), "summary".into());
        }
        super::common::out(&format!("{v}\n"))?;
    } else {
        super::common::outln!(
            "watch: {} cycle(s), {} image(s){}; process ok {} nok {} not evaluated {}; {} finding(s), {} alarm(s) raised",
            s.cycles,
            s.images,
            s.yields
                .as_ref()
                .map(|y| format!(" ({})", y.summary_line()))
                .unwrap_or_default(),
            s.process_ok,
            s.process_nok,
            s.process_not_evaluated,
            s.findings,
            s.alarms_raised
        )?;
    }
    Ok(ExitCode::SUCCESS)
}
