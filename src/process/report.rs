//! A monitor run in the forms a line engineer reads: the text summary
//! (verdict counts, every NOK cycle with its reasons, the cycles not
//! evaluated, the SPC table with Cpk bands and run-rule alarms) and CSV
//! tables (one row per cycle, one per characteristic).

use super::monitor::{Characteristic, CycleStatus};
use super::run::MonitorRun;
use super::spc::cpk_band;
use super::story::{Confusion, StoryReport};
use crate::vision::batch::ItemStatus;
use std::fmt::Write;

/// NOK cycles listed one by one in the text (the CSV has them all).
pub const MAX_LISTED: usize = 20;

fn opt(x: Option<f64>, digits: usize) -> String {
    x.map_or("–".into(), |v| format!("{v:.digits$}"))
}

fn spc_table(out: &mut String, title: &str, spc: &[Characteristic]) {
    if spc.is_empty() {
        return;
    }
    let _ = writeln!(out, "\n{title}");
    let _ = writeln!(
        out,
        "  {:<24} {:>5} {:>11} {:>9} {:>9} {:>6} {:>6} {:>6} {:>6}  {:<10} alarms",
        "characteristic",
        "n",
        "mean",
        "σ within",
        "σ overall",
        "Cp",
        "Cpk",
        "Pp",
        "Ppk",
        "Cpk band"
    );
    for c in spc {
        let Some(k) = &c.capability else {
            let _ = writeln!(out, "  {:<24} (fewer than two values)", c.name);
            continue;
        };
        let alarms = c.chart.as_ref().map_or(0, |ch| ch.alarms.len());
        let _ = writeln!(
            out,
            "  {:<24} {:>5} {:>9.4} {:<2}{:>9.4} {:>9.4} {:>6} {:>6} {:>6} {:>6}  {:<10} {}",
            c.name,
            k.n,
            k.mean,
            c.unit,
            k.sigma_within,
            k.sigma_overall,
            opt(k.cp, 2),
            opt(k.cpk, 2),
            opt(k.pp, 2),
            opt(k.ppk, 2),
            k.cpk.map_or("–", cpk_band),
            alarms
        );
        if let Some(ch) = &c.chart {
            for a in ch.alarms.iter().take(5) {
                let _ = writeln!(out, "      rule {}: {}", a.rule, a.text);
            }
        }
    }
}

/// The text summary of a run.
pub fn summary_text(run: &MonitorRun) -> String {
    let mut out = String::new();
    let total = run.ok + run.nok + run.not_evaluated;
    let _ = writeln!(
        out,
        "Process monitor: {} — {} cycle(s): {} OK, {} NOK, {} not evaluated",
        run.part_number, total, run.ok, run.nok, run.not_evaluated
    );
    if let Some(l) = &run.learned {
        let _ = writeln!(out, "  {l}");
    }
    for l in &run.logs {
        let r = match &l.report {
            Err(e) => {
                let _ = writeln!(out, "\n{}: not monitored: {e}", l.file);
                continue;
            }
            Ok(r) => r,
        };
        let _ = writeln!(
            out,
            "\n{} (lot {}): {} OK, {} NOK, {} not evaluated",
            l.file,
            l.lot.as_deref().unwrap_or("–"),
            r.ok,
            r.nok,
            r.not_evaluated
        );
        for o in r.by_object.iter().filter(|o| o.nok > 0) {
            let _ = writeln!(out, "  {} '{}': NOK on {} cycle(s)", o.kind, o.name, o.nok);
        }
        let noks: Vec<_> = r
            .cycles
            .iter()
            .filter(|c| c.status == CycleStatus::Nok)
            .collect();
        for c in noks.iter().take(MAX_LISTED) {
            let why: Vec<String> = c
                .failed
                .iter()
                .map(|f| {
                    format!(
                        "{} '{}': {}",
                        f.kind,
                        f.name,
                        f.reason.as_deref().unwrap_or("")
                    )
                })
                .collect();
            let _ = writeln!(out, "  cycle {:>6} NOK  {}", c.index, why.join("; "));
        }
        if noks.len() > MAX_LISTED {
            let _ = writeln!(
                out,
                "  … {} more NOK cycles (--csv lists them all)",
                noks.len() - MAX_LISTED
            );
        }
        for c in r
            .cycles
            .iter()
            .filter(|c| c.status == CycleStatus::NotEvaluated)
            .take(MAX_LISTED)
        {
            let _ = writeln!(
                out,
                "  cycle {:>6} not evaluated: {}",
                c.index,
                c.why_not.as_deref().unwrap_or("")
            );
        }
        for n in &r.notes {
            let _ = writeln!(out, "  note: {n}");
        }
        if let Some(st) = &l.story {
            story_text(&mut out, st);
        }
    }
    if let (Some(c), true) = (&run.confusion, run.logs.len() > 1) {
        let _ = writeln!(out, "\nConnectors, all logs:");
        confusion_text(&mut out, c);
    }
    spc_table(&mut out, "SPC (all logs)", &run.spc);
    if run.spc_by_lot.len() > 1 {
        for (lot, spc) in &run.spc_by_lot {
            spc_table(&mut out, &format!("SPC, lot {lot}"), spc);
        }
    }
    if run.spc_by_speed.len() > 1 {
        for (speed, spc) in &run.spc_by_speed {
            spc_table(&mut out, &format!("SPC, {speed}"), spc);
        }
    }
    pin_spc_text(&mut out, run);
    out
}

/// Characteristics listed by lowest Cpk in the text (the CSV has them all).
pub const PIN_SPC_LISTED: usize = 10;

/// The pins' capability in Cpk order, lowest first (no Cpk last).
pub fn by_cpk(spc: &[Characteristic]) -> Vec<&Characteristic> {
    let mut v: Vec<&Characteristic> = spc.iter().collect();
    let key = |c: &Characteristic| c.capability.as_ref().and_then(|k| k.cpk);
    v.sort_by(|a, b| match (key(a), key(b)) {
        (Some(x), Some(y)) => x.total_cmp(&y),
        (Some(_), None) => std::cmp::Ordering::Less,
        (None, Some(_)) => std::cmp::Ordering::Greater,
        (None, None) => std::cmp::Ordering::Equal,
    });
    v
}

/// How many characteristics fall in each Cpk band (capable, adequate,
/// inadequate).
pub fn band_counts(spc: &[Characteristic]) -> [usize; 3] {
    let mut n = [0; 3];
    for k in spc.iter().filter_map(|c| c.capability.as_ref()?.cpk) {
        n[match cpk_band(k) {
            "capable" => 0,
            "adequate" => 1,
            _ => 2,
        }] += 1;
    }
    n
}

fn pin_spc_text(out: &mut String, run: &MonitorRun) {
    if run.pin_spc.is_empty() {
        return;
    }
    let connectors: usize = run
        .logs
        .iter()
        .filter_map(|l| l.story.as_ref())
        .map(|s| s.pins.len())
        .sum();
    let [cap, adq, inadq] = band_counts(&run.pin_spc);
    let _ = writeln!(
        out,
        "\nPin positions: {} characteristics over {connectors} photographed connectors \
         (true position = 2 × radial offset, against 2 × position_mm): \
         Cpk capable {cap}, adequate {adq}, inadequate {inadq}",
        run.pin_spc.len()
    );
    let worst: Vec<Characteristic> = by_cpk(&run.pin_spc)
        .into_iter()
        .take(PIN_SPC_LISTED)
        .cloned()
        .collect();
    spc_table(
        out,
        &format!(
            "Pin SPC, the {} lowest Cpk (spc.csv lists all)",
            worst.len()
        ),
        &worst,
    );
}

fn confusion_text(out: &mut String, c: &Confusion) {
    let _ = writeln!(
        out,
        "  {:<16} {:>12} {:>12}",
        "", "vision pass", "vision fail"
    );
    let _ = writeln!(
        out,
        "  {:<16} {:>12} {:>12}",
        "process OK", c.process_ok_vision_pass, c.process_ok_vision_fail
    );
    let _ = writeln!(
        out,
        "  {:<16} {:>12} {:>12}",
        "process NOK", c.process_nok_vision_pass, c.process_nok_vision_fail
    );
    if let Some(r) = c.process_recall_of_vision_fails() {
        let _ = writeln!(
            out,
            "  the force curve flagged {:.1} % of the connectors vision failed",
            100.0 * r
        );
    }
}

fn story_text(out: &mut String, st: &StoryReport) {
    let _ = writeln!(out, "  connectors (process × vision):");
    confusion_text(out, &st.confusion);
    let dis: Vec<_> = st.disagreements().collect();
    for c in dis.iter().take(MAX_LISTED) {
        let p = match c.process {
            Some(CycleStatus::Nok) => "process NOK",
            _ => "process OK",
        };
        let v = match c.vision {
            Some(ItemStatus::Fail) => "vision fail",
            _ => "vision pass",
        };
        let _ = writeln!(out, "  cycle {:>6} {p}, {v}: {}", c.cycle, c.why());
    }
    if dis.len() > MAX_LISTED {
        let _ = writeln!(
            out,
            "  … {} more disagreements (connectors.csv lists them all)",
            dis.len() - MAX_LISTED
        );
    }
    if st.cycles_without_image > 0 {
        let _ = writeln!(
            out,
            "  {} cycle(s) without a photograph",
            st.cycles_without_image
        );
    }
    for i in st.images_without_cycle.iter().take(MAX_LISTED) {
        let _ = writeln!(out, "  image not joined: {i}");
    }
}

/// One row per connector: log, cycle, process status, vision status,
/// agreement, both sides' reasons.
pub fn connectors_csv(run: &MonitorRun) -> String {
    let mut out = String::from(
        "file,cycle,process,vision,agree,process_reasons,vision_reasons,stroke_in_band,force_in_band,stroke_rms_err_mm,stroke_err_bdc_mm\n",
    );
    for st in run.logs.iter().filter_map(|l| l.story.as_ref()) {
        for c in &st.connectors {
            let status = |s: Option<&str>| s.unwrap_or("").to_string();
            let b = |f: fn(&super::story::BandFit) -> f64| {
                c.band.as_ref().map_or(String::new(), |b| f(b).to_string())
            };
            let _ = writeln!(
                out,
                "{},{},{},{},{},{},{},{},{},{},{}",
                csv_field(&c.log),
                c.cycle,
                status(c.process.map(CycleStatus::name)),
                status(c.vision.map(|v| match v {
                    ItemStatus::Pass => "pass",
                    ItemStatus::Fail => "fail",
                    ItemStatus::Error => "error",
                })),
                c.agree.map_or(String::new(), |a| a.to_string()),
                csv_field(&c.process_reasons.join("; ")),
                csv_field(&c.vision_reasons.join("; ")),
                b(|b| b.stroke_in_band),
                b(|b| b.force_in_band),
                b(|b| b.stroke_rms_err_mm),
                b(|b| b.stroke_err_bdc_mm)
            );
        }
    }
    out
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// One row per cycle: file, lot, index, time, speed, status, reasons, and
/// every value check's value.
pub fn cycles_csv(run: &MonitorRun) -> String {
    let names: Vec<String> = run.spc.iter().map(|c| c.name.clone()).collect();
    let mut out = String::from("file,lot,cycle,t_start_ns,motor_rpm,status,reasons");
    for n in &names {
        out.push(',');
        out.push_str(&csv_field(n));
    }
    out.push('\n');
    for l in &run.logs {
        let Ok(r) = &l.report else { continue };
        for c in &r.cycles {
            let status = c.status.name();
            let reasons = c.reasons().join("; ");
            let _ = write!(
                out,
                "{},{},{},{},{:.3},{},{}",
                csv_field(&l.file),
                csv_field(l.lot.as_deref().unwrap_or("")),
                c.index,
                c.t_start_ns,
                c.motor_rpm,
                status,
                csv_field(&reasons)
            );
            for n in &names {
                out.push(',');
                if let Some(v) = c.values.get(n) {
                    let _ = write!(out, "{v}");
                }
            }
            out.push('\n');
        }
    }
    out
}

/// One row per characteristic: the process values over all logs, by lot,
/// by speed; then the pins' positions the same way.
pub fn spc_csv(run: &MonitorRun) -> String {
    let mut out = String::from(
        "scope,characteristic,quantity,unit,n,subgroup,mean,sigma_within,sigma_overall,lsl,usl,cp,cpk,pp,ppk,cpk_band,cl,ucl,lcl,alarms\n",
    );
    let rows = std::iter::once(("all", &run.spc))
        .chain(run.spc_by_lot.iter().map(|(k, v)| (k.as_str(), v)))
        .chain(run.spc_by_speed.iter().map(|(k, v)| (k.as_str(), v)))
        .chain(std::iter::once(("all", &run.pin_spc)))
        .chain(run.pin_spc_by_lot.iter().map(|(k, v)| (k.as_str(), v)))
        .chain(run.pin_spc_by_speed.iter().map(|(k, v)| (k.as_str(), v)));
    let o = |x: Option<f64>| x.map_or(String::new(), |v| v.to_string());
    for (scope, spc) in rows {
        for c in spc {
            let Some(k) = &c.capability else { continue };
            let ch = c.chart.as_ref();
            let _ = writeln!(
                out,
                "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                csv_field(scope),
                csv_field(&c.name),
                c.quantity,
                c.unit,
                k.n,
                k.subgroup,
                k.mean,
                k.sigma_within,
                k.sigma_overall,
                o(k.lsl),
                o(k.usl),
                o(k.cp),
                o(k.cpk),
                o(k.pp),
                o(k.ppk),
                k.cpk.map_or("", cpk_band),
                o(ch.map(|c| c.cl)),
                o(ch.map(|c| c.ucl)),
                o(ch.map(|c| c.lcl)),
                ch.map_or(0, |c| c.alarms.len())
            );
        }
    }
    out
}
