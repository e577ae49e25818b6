//! `pinsight log LOG.mcap... [--channels MAP.toml] [--json]`: loads rig logs
//! and prints what they hold — metadata, channels with counts, spans and
//! rates, cycles, sensor zeros, images, attachments and every finding.
//!
//! Exit code: 0 when every log loaded `ok` or `ok_with_warnings`, 1 when a
//! log is `partial` or `error` (data lost or nothing usable), 2 when a file
//! could not be read at all (each file is still reported; the others go on).

use crate::cli::common::{outln, outp};
use crate::model::Params;
use crate::model::kinematics::Geometry;
use crate::progress::{Progress, ProgressBarGuard};
use crate::rig::cycles::{CycleOptions, CycleSource, OffsetEstimate, ValueSource, analyse};
use crate::rig::summary::{LogSummary, summarize, utc_string};
use crate::rig::{LoadStatus, Severity, load};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Rig logs (MCAP).
    #[arg(required = true, value_name = "LOG.mcap")]
    pub inputs: Vec<PathBuf>,
    #[command(flatten)]
    pub log_read: super::common::LogReadArgs,
    /// Print JSON (one object per log; an array for several logs).
    #[arg(long)]
    pub json: bool,
    /// Mechanism parameters (TOML, as `simulate` reads) for the ideal stroke; default: preset paper.
    #[arg(long, value_name = "FILE")]
    pub params: Option<PathBuf>,
    /// Crank-angle grid points per revolution.
    #[arg(long, default_value_t = 720, value_parser = super::common::bounds::points)]
    pub points: usize,
    /// List every cycle (default: the first and last five).
    #[arg(long)]
    pub all_cycles: bool,
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let opts = args.log_read.load_options()?;
    let params = match &args.params {
        Some(p) => Params::from_toml_file(p).map_err(|e| anyhow::anyhow!("{e}"))?,
        None => Params::paper(),
    };
    let copts = CycleOptions {
        geometry: Geometry::of(&params),
        points_per_rev: args.points.max(8),
        ..CycleOptions::default()
    };
    let mut summaries = Vec::new();
    let mut code = 0u8;
    for path in &args.inputs {
        let progress = Progress::new(0);
        let log = {
            let _bar = ProgressBarGuard::start(progress.clone(), "loading");
            load(path, &opts, &progress)
        };
        match log {
            Ok(log) => {
                let cycles = analyse(&log, &copts);
                let s = summarize(&log, Some(&cycles));
                if matches!(s.load_status, LoadStatus::Partial | LoadStatus::Error) {
                    code = code.max(1);
                }
                if args.json {
                    summaries.push(s);
                } else {
                    outp!("{}", render_text(&s, args.all_cycles))?;
                }
            }
            Err(e) => {
                code = 2;
                eprintln!("error: {e}");
            }
        }
    }
    if args.json {
        let text = if summaries.len() == 1 {
            serde_json::to_string_pretty(&summaries[0])?
        } else {
            serde_json::to_string_pretty(&summaries)?
        };
        outln!("{text}")?;
    }
    Ok(ExitCode::from(code))
}

fn opt<T: std::fmt::Display>(v: &Option<T>) -> String {
    v.as_ref().map_or("—".into(), |x| x.to_string())
}

fn opt_num(v: Option<f64>) -> String {
    v.map_or("—".into(), crate::fmt::plain)
}

fn source_name(s: ValueSource) -> &'static str {
    match s {
        ValueSource::Override => "override",
        ValueSource::Metadata => "metadata",
        ValueSource::Estimated => "estimated",
        ValueSource::Default => "default",
        ValueSource::Unavailable => "unavailable",
    }
}

fn offset_line(o: &OffsetEstimate, scale: f64, unit: &str, digits: usize) -> String {
    let mut s = format!(
        "{:<16} {:>10.*} {unit}  ({})",
        o.name,
        digits,
        o.applied * scale,
        source_name(o.source)
    );
    if let (Some(e), Some(sg)) = (o.estimate, o.sigma) {
        let _ = write!(
            s,
            "; estimate {:.*} ± {:.*} {unit}",
            digits,
            e * scale,
            digits,
            sg * scale
        );
    }
    if let Some(m) = o.metadata {
        let _ = write!(s, "; metadata {:.*} {unit}", digits, m * scale);
    }
    s
}

/// The technician's text view of a summary.
pub fn render_text(s: &LogSummary, all_cycles: bool) -> String {
    let mut o = String::new();
    let _ = writeln!(o, "{} — {}", s.file, s.status);
    let c = &s.container;
    let _ = writeln!(
        o,
        "  file       {} bytes; profile '{}', written by {}; {}; summary {}; end magic {}",
        c.file_size,
        c.profile.clone().unwrap_or_default(),
        opt(&c.library),
        if c.chunked {
            format!(
                "{} chunk(s) ({})",
                c.chunks,
                c.compressions
                    .iter()
                    .map(|x| if x.is_empty() {
                        "uncompressed"
                    } else {
                        x.as_str()
                    })
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        } else {
            "not chunked".into()
        },
        if c.summary {
            if c.statistics {
                "with statistics"
            } else {
                "without statistics"
            }
        } else {
            "none"
        },
        if c.end_magic { "yes" } else { "no" }
    );
    if let (Some(a), Some(b)) = (s.log_start_ns, s.log_end_ns) {
        let _ = writeln!(
            o,
            "  time       {} UTC, {:.3} s (log_time {a} … {b})",
            utc_string(a),
            (b - a) as f64 * 1e-9
        );
    }
    let m = &s.meta;
    if m.present || !m.overridden.is_empty() {
        let _ = writeln!(
            o,
            "  metadata   rig {}, part {}, lot {}; clearance {} mm, material {}, motor {} rpm, gear {}, standoff {} mm{}{}{}",
            opt(&m.rig_id),
            opt(&m.part_number),
            opt(&m.lot),
            opt_num(m.clearance_mm),
            opt(&m.material),
            opt_num(m.motor_rpm),
            opt_num(m.gear_ratio),
            opt_num(m.standoff_mm),
            m.laser_zero_mm.map_or(String::new(), |v| format!(
                ", laser zero {} mm",
                crate::fmt::plain(v)
            )),
            m.force_tare_n.map_or(String::new(), |v| format!(
                ", force tare {} N",
                crate::fmt::plain(v)
            )),
            m.angle_offset_rad.map_or(String::new(), |v| format!(
                ", angle offset {} rad",
                crate::fmt::plain(v)
            )),
        );
        let extra: BTreeMap<&String, &String> = m
            .raw
            .iter()
            .filter(|(k, _)| !crate::rig::meta::KNOWN_KEYS.contains(&k.as_str()))
            .collect();
        if !extra.is_empty() {
            let _ = writeln!(
                o,
                "             other keys: {}",
                extra
                    .iter()
                    .map(|(k, v)| format!("{k}={v}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
        if !m.overridden.is_empty() {
            let _ = writeln!(
                o,
                "             overridden by the session: {}",
                m.overridden.join(", ")
            );
        }
    } else {
        let _ = writeln!(o, "  metadata   none (no 'rig' record)");
    }
    let _ = writeln!(o, "  channel map {}", s.channel_map);

    let _ = writeln!(o, "\nChannels");
    let _ = writeln!(
        o,
        "  {:<20} {:<14} {:<24} {:>9} {:>9} {:>9} {:>9} {:>5} {:>7} {:>5}",
        "topic",
        "used as",
        "schema",
        "messages",
        "samples",
        "rate Hz",
        "span s",
        "dup",
        "invalid",
        "gaps"
    );
    for ch in &s.channels {
        let sigs: Vec<_> = s.signals.iter().filter(|x| x.topic == ch.topic).collect();
        let samples = sigs
            .first()
            .map_or("—".to_string(), |x| x.samples.to_string());
        let rate = sigs
            .first()
            .and_then(|x| x.rate_hz)
            .or(ch.rate_hz)
            .map_or("—".to_string(), |r| format!("{r:.1}"));
        let span = match (ch.first_ns, ch.last_ns) {
            (Some(a), Some(b)) => format!("{:.4}", (b - a) as f64 * 1e-9),
            _ => "—".into(),
        };
        let dup = sigs.first().map_or(0, |x| x.duplicates);
        let invalid: u64 = sigs.iter().map(|x| x.invalid.total()).sum();
        let gaps = sigs.first().map_or(0, |x| x.gap_count);
        let used = if ch.used_as.is_empty() {
            "—".to_string()
        } else {
            ch.used_as.join(", ")
        };
        let _ = writeln!(
            o,
            "  {:<20} {:<14} {:<24} {:>9} {:>9} {:>9} {:>9} {:>5} {:>7} {:>5}",
            ch.topic,
            used,
            format!("{} ({})", opt(&ch.schema), ch.message_encoding),
            ch.messages,
            samples,
            rate,
            span,
            dup,
            invalid,
            gaps
        );
    }

    if let Some(cs) = &s.cycles {
        let _ = writeln!(
            o,
            "\nCycles     {} complete ({} usable), {}; indices {}..{}",
            cs.count,
            cs.usable,
            match cs.source {
                CycleSource::Marks => "from the /rig/cycle marks",
                CycleSource::Angle => "from the crank angle (TDC crossings)",
                CycleSource::None => "none found",
            },
            opt(&cs.first_index),
            opt(&cs.last_index)
        );
        if cs.count > 0 {
            let k = &cs.crank;
            let _ = writeln!(
                o,
                "  speed      crank {:.2} rpm, motor {:.2} rpm (gear {} {}; speed from {}; cycle means {:.2}–{:.2}, spread {:.3} %){}",
                k.crank_rpm_mean,
                k.motor_rpm_mean,
                k.gear_ratio,
                k.gear_ratio_source.map_or("", source_name),
                k.speed_source,
                k.motor_rpm_cycle_min,
                k.motor_rpm_cycle_max,
                k.speed_spread_rel * 100.0,
                k.motor_rpm_setpoint.map_or(String::new(), |v| format!(
                    "; set-point {} rpm",
                    crate::fmt::plain(v)
                ))
            );
            let _ = writeln!(
                o,
                "  angle      {}{}; standoff {} mm ({})",
                if k.wrapped_input {
                    "wrapped input, unwrapped"
                } else {
                    "unwrapped input"
                },
                k.encoder_counts
                    .map_or(String::new(), |n| format!(", encoder {n} counts/rev")),
                crate::fmt::plain(cs.standoff_mm),
                source_name(cs.standoff_source)
            );
        }
        let off = &cs.offsets;
        let _ = writeln!(o, "  sensor zeros");
        let _ = writeln!(
            o,
            "    {}",
            offset_line(&off.angle_offset_rad, 180.0 / std::f64::consts::PI, "°", 3)
        );
        let _ = writeln!(o, "    {}", offset_line(&off.laser_zero_mm, 1.0, "mm", 4));
        let mut ft = offset_line(&off.force_tare_n, 1.0, "N", 4);
        if let (Some(a), Some(b)) = (off.force_tare_start_n, off.force_tare_end_n) {
            let _ = write!(ft, "; {a:.4} N at the start, {b:.4} N at the end");
        }
        let _ = writeln!(o, "    {ft}");
        if !cs.cycles.is_empty() {
            let _ = writeln!(
                o,
                "  {:>6} {:>9} {:>9} {:>9} {:>8} {:>9} {:>9} {:>9} {:>9} {:>9}  notes",
                "cycle",
                "t s",
                "motor rpm",
                "ripple %",
                "depth mm",
                "peak N",
                "TDC err",
                "BDC err",
                "dev rms",
                "dev max"
            );
            let n = cs.cycles.len();
            for (i, r) in cs.cycles.iter().enumerate() {
                if !all_cycles && n > 10 && i == 5 {
                    let _ = writeln!(o, "  {:>6} ({} more; --all-cycles lists them)", "…", n - 10);
                }
                if !all_cycles && n > 10 && (5..n - 5).contains(&i) {
                    continue;
                }
                let mut notes = Vec::new();
                if !r.usable {
                    notes.push(format!(
                        "unusable: angle off TDC by {:.1}° at a mark",
                        r.mark_mismatch_deg.unwrap_or(f64::NAN)
                    ));
                }
                if r.stroke_coverage < 0.999 {
                    notes.push(format!("stroke {:.0} %", r.stroke_coverage * 100.0));
                }
                if r.force_coverage < 0.999 && !r.peak_force_n.is_nan() {
                    notes.push(format!("force {:.0} %", r.force_coverage * 100.0));
                }
                let _ = writeln!(
                    o,
                    "  {:>6} {:>9.4} {:>9.2} {:>9.3} {:>8.3} {:>9.3} {:>9.4} {:>9.4} {:>9.4} {:>9.4}  {}",
                    r.index,
                    r.t_start_s,
                    r.motor_rpm_mean,
                    r.ripple_first_harmonic * 100.0,
                    r.depth_mm,
                    r.peak_force_n,
                    r.stroke_err_tdc_mm,
                    r.stroke_err_bdc_mm,
                    r.stroke_dev_rms_mm,
                    r.stroke_dev_max_mm,
                    notes.join("; ")
                );
            }
            let _ = writeln!(
                o,
                "  (ripple: first harmonic of the motor speed over the cycle; errors and deviations: measured stroke − ideal stroke, mm)"
            );
        }
    }

    if !s.images.is_empty() {
        let mut formats: BTreeMap<&str, usize> = BTreeMap::new();
        for i in &s.images {
            *formats.entry(i.format.as_str()).or_default() += 1;
        }
        let cyc: Vec<u64> = s.images.iter().filter_map(|i| i.cycle).collect();
        let _ = writeln!(
            o,
            "\nImages     {} on {} ({}); cycles {}",
            s.images.len(),
            s.images[0].topic,
            formats
                .iter()
                .map(|(k, v)| format!("{k} {v}"))
                .collect::<Vec<_>>()
                .join(", "),
            match (cyc.first(), cyc.last()) {
                (Some(a), Some(b)) => format!("{a}..{b} ({} tagged)", cyc.len()),
                _ => "not tagged".into(),
            }
        );
    }
    if !s.attachments.is_empty() {
        let _ = writeln!(o, "\nAttachments");
        for a in &s.attachments {
            let _ = writeln!(
                o,
                "  {} ({}, {} bytes): {:?}",
                a.name, a.media_type, a.size, a.kind
            );
        }
    }
    let _ = writeln!(o, "\nFindings ({})", s.findings.len());
    for f in &s.findings {
        let tag = match f.severity {
            Severity::Info => "info   ",
            Severity::Warning => "WARNING",
            Severity::DataLoss => "DATA LOSS",
            Severity::Error => "ERROR  ",
        };
        let _ = writeln!(o, "  [{tag}] {}", f.message);
    }
    let _ = writeln!(o);
    o
}
