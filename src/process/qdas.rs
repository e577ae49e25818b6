//! A monitor run as a Q-DAS ASCII transfer file (AQDEF, `.dfq`), the
//! format quality departments' SPC packages (Q-DAS qs-STAT/procella and
//! their readers) import: one part, one characteristic per value check,
//! one value per evaluated cycle with its date/time and batch.
//!
//! Fields written (AQDEF K-field form, `Kxxxx/i` for characteristic i):
//!
//! | field | what |
//! |---|---|
//! | K0100 | number of characteristics |
//! | K1001/1, K1002/1 | part number, part description |
//! | K2001/i, K2002/i | characteristic number (the quantity), description (the check's name) |
//! | K2004/i | characteristic type: 0 = variable |
//! | K2110/i, K2111/i | lower and upper specification limit (when the check has them) |
//! | K2142/i | unit |
//! | K2022/i | decimal places of the values |
//! | K0001/i | a value |
//! | K0004/i | its date/time, `DD.MM.YYYY/HH:MM:SS` (UTC, from the cycle's start) |
//! | K0006/i | its batch (the log's `lot`) |
//! | K0014/i | its part identification (`<log file name>#cycle-<index>`) |
//!
//! Values go record by record (one cycle: every characteristic it has a
//! value for, the process values then its connector's pins), in log then
//! cycle order, as the run's SPC reads them. Cycles
//! NOK are exported too (SPC sees the process as it ran); cycles not
//! evaluated have no values. Text is Latin-1 (`µ` is 0xB5; a character
//! Latin-1 lacks becomes `?`), lines end in CR LF, numbers use a point.

use super::pin_spc::{ConnectorPins, PinMeasure};
use super::run::MonitorRun;
use std::fmt::Write;

/// Decimal places written for every value (enough for µm on a mm value).
pub const DECIMALS: usize = 6;

/// `DD.MM.YYYY/HH:MM:SS` (UTC) of a time in ns since the Unix epoch.
pub fn qdas_time(t_ns: i64) -> String {
    let (y, m, d, hh, mm, ss, _) = crate::fmt::utc_civil(t_ns);
    format!("{d:02}.{m:02}.{y:04}/{hh:02}:{mm:02}:{ss:02}")
}

/// A field's text on one line (AQDEF fields end at the line end).
fn one_line(s: &str) -> String {
    s.replace(['\r', '\n'], " ")
}

/// The run as AQDEF text (before the Latin-1 encoding of [`dfq`]).
pub fn dfq_text(run: &MonitorRun) -> String {
    let mut out = String::new();
    let mut line = |s: String| {
        out.push_str(&s);
        out.push_str("\r\n");
    };
    let chars: Vec<&super::monitor::Characteristic> = run.spc.iter().chain(&run.pin_spc).collect();
    let index: std::collections::HashMap<&str, usize> = chars
        .iter()
        .enumerate()
        .map(|(i, c)| (c.name.as_str(), i + 1))
        .collect();
    line(format!("K0100 {}", chars.len()));
    line(format!("K1001/1 {}", one_line(&run.part_number)));
    line("K1002/1 pinsight monitor: insertion process values".to_string());
    for (i, c) in chars.iter().enumerate() {
        let k = i + 1;
        line(format!("K2001/{k} {}", c.quantity));
        line(format!("K2002/{k} {}", one_line(&c.name)));
        line(format!("K2004/{k} 0"));
        if let Some(cap) = &c.capability {
            if let Some(l) = cap.lsl {
                line(format!("K2110/{k} {l}"));
            }
            if let Some(u) = cap.usl {
                line(format!("K2111/{k} {u}"));
            }
        }
        line(format!("K2142/{k} {}", c.unit));
        line(format!("K2022/{k} {DECIMALS}"));
    }
    for l in &run.logs {
        let Ok(r) = &l.report else { continue };
        let file = std::path::Path::new(&l.file)
            .file_name()
            .map_or(l.file.clone(), |f| f.to_string_lossy().into_owned());
        let pins: std::collections::HashMap<u64, &ConnectorPins> = l
            .story
            .iter()
            .flat_map(|s| &s.pins)
            .map(|c| (c.cycle, c))
            .collect();
        for cy in &r.cycles {
            // The process values (characteristics 1 … spc.len()), then the pins'.
            let mut record: Vec<(usize, f64)> = run
                .spc
                .iter()
                .enumerate()
                .filter_map(|(i, c)| Some((i + 1, *cy.values.get(&c.name)?)))
                .collect();
            for p in pins.get(&cy.index).map_or(&[][..], |c| &c.pins) {
                for m in PinMeasure::ALL {
                    if let (Some(v), Some(&k)) =
                        (m.value(p), index.get(m.char_name(p.row, p.col).as_str()))
                    {
                        record.push((k, v));
                    }
                }
            }
            for (k, v) in record.into_iter().filter(|(_, v)| v.is_finite()) {
                let mut rec = String::new();
                let _ = write!(rec, "K0001/{k} {v:.DECIMALS$}");
                line(rec);
                line(format!("K0004/{k} {}", qdas_time(cy.t_start_ns)));
                if let Some(lot) = &l.lot {
                    line(format!("K0006/{k} {}", one_line(lot)));
                }
                line(format!("K0014/{k} {}#cycle-{}", one_line(&file), cy.index));
            }
        }
    }
    out
}

/// The `.dfq` file's bytes (Latin-1).
pub fn dfq(run: &MonitorRun) -> Vec<u8> {
    dfq_text(run)
        .chars()
        .map(|c| u8::try_from(u32::from(c)).unwrap_or(b'?'))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dates_are_the_civil_calendar() {
        // 2026-11-20T13:05:01Z and the leap day 2024-02-29T00:00:00Z, the epoch.
        assert_eq!(qdas_time(1_795_179_901_000_000_000), "20.11.2026/13:05:01");
        assert_eq!(qdas_time(1_709_164_800_000_000_000), "29.02.2024/00:00:00");
        assert_eq!(qdas_time(0), "01.01.1970/00:00:00");
        assert_eq!(qdas_time(-1_000_000_000), "31.12.1969/23:59:59");
    }
}
