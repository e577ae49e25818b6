//! The summary of a log (what `pinsight log` prints and the Session pane
//! shows): everything of [`RigLog`] and [`CycleSet`] except the sample
//! arrays and grids, as plain data.

use super::cycles::{CrankInfo, CycleSet, CycleSource, SensorOffsets, ValueSource};
use super::load::{ChannelInfo, ImageRef, LogAttachment, RigLog};
use super::mcap_read::ContainerInfo;
use super::meta::RigMeta;
use super::report::{Finding, LoadStatus, ReadCounts, status_of};
use super::signals::SignalStats;
use serde::Serialize;

/// One cycle's figures (no grids).
#[derive(Debug, Clone, Serialize)]
pub struct CycleRow {
    pub index: u64,
    /// Start, seconds from the log start.
    pub t_start_s: f64,
    pub duration_s: f64,
    pub motor_rpm_mean: f64,
    pub ripple_rms: f64,
    pub ripple_first_harmonic: f64,
    pub depth_mm: f64,
    pub peak_force_n: f64,
    pub stroke_err_tdc_mm: f64,
    pub stroke_err_bdc_mm: f64,
    pub stroke_dev_rms_mm: f64,
    pub stroke_dev_max_mm: f64,
    pub stroke_coverage: f64,
    pub force_coverage: f64,
    pub mark_mismatch_deg: Option<f64>,
    pub usable: bool,
}

/// The cycles of a log, summarised.
#[derive(Debug, Clone, Serialize)]
pub struct CycleSummary {
    pub source: CycleSource,
    pub count: usize,
    pub usable: usize,
    pub first_index: Option<u64>,
    pub last_index: Option<u64>,
    pub points_per_rev: usize,
    pub standoff_mm: f64,
    pub standoff_source: ValueSource,
    pub crank: CrankInfo,
    pub offsets: SensorOffsets,
    pub cycles: Vec<CycleRow>,
}

/// What a log holds, for people and programs.
#[derive(Debug, Clone, Serialize)]
pub struct LogSummary {
    pub file: String,
    /// Worst of the load status and the cycle analysis's findings.
    pub status: LoadStatus,
    /// Status of the load alone.
    pub load_status: LoadStatus,
    pub container: ContainerInfo,
    pub meta: RigMeta,
    pub channel_map: String,
    pub log_start_ns: Option<i64>,
    pub log_end_ns: Option<i64>,
    pub duration_s: f64,
    pub channels: Vec<ChannelInfo>,
    pub signals: Vec<SignalStats>,
    pub cycles: Option<CycleSummary>,
    pub images: Vec<ImageRef>,
    pub attachments: Vec<LogAttachment>,
    pub counts: ReadCounts,
    /// Load findings, then cycle findings.
    pub findings: Vec<Finding>,
}

/// Summarises a loaded log and (optionally) its cycles.
pub fn summarize(log: &RigLog, cycles: Option<&CycleSet>) -> LogSummary {
    let mut findings = log.report.findings.clone();
    let cs = cycles.map(|c| {
        findings.extend(c.findings.iter().cloned());
        let t0 = log.log_start_ns.unwrap_or(0);
        CycleSummary {
            source: c.source,
            count: c.cycles.len(),
            usable: c.usable().count(),
            first_index: c.cycles.first().map(|x| x.index),
            last_index: c.cycles.last().map(|x| x.index),
            points_per_rev: c.points_per_rev,
            standoff_mm: c.standoff_mm,
            standoff_source: c.standoff_source,
            crank: c.crank.clone(),
            offsets: c.offsets.clone(),
            cycles: c
                .cycles
                .iter()
                .map(|y| CycleRow {
                    index: y.index,
                    t_start_s: (y.t_start_ns - t0) as f64 * 1e-9,
                    duration_s: y.duration_s,
                    motor_rpm_mean: y.motor_rpm_mean,
                    ripple_rms: y.ripple_rms,
                    ripple_first_harmonic: y.ripple_first_harmonic,
                    depth_mm: y.depth_mm,
                    peak_force_n: y.peak_force_n,
                    stroke_err_tdc_mm: y.stroke_err_tdc_mm,
                    stroke_err_bdc_mm: y.stroke_err_bdc_mm,
                    stroke_dev_rms_mm: y.stroke_dev_rms_mm,
                    stroke_dev_max_mm: y.stroke_dev_max_mm,
                    stroke_coverage: y.stroke_coverage,
                    force_coverage: y.force_coverage,
                    mark_mismatch_deg: y.mark_mismatch_deg,
                    usable: y.usable,
                })
                .collect(),
        }
    });
    LogSummary {
        file: log.file.clone(),
        status: status_of(&findings),
        load_status: log.report.status,
        container: log.container.clone(),
        meta: log.meta.clone(),
        channel_map: log.channel_map.source.clone(),
        log_start_ns: log.log_start_ns,
        log_end_ns: log.log_end_ns,
        duration_s: log.duration_s(),
        channels: log.channels.clone(),
        signals: log.stats.clone(),
        cycles: cs,
        images: log.images.clone(),
        attachments: log.attachments.clone(),
        counts: log.report.counts.clone(),
        findings,
    }
}

/// UTC calendar date and time of ns since the Unix epoch, `YYYY-MM-DD hh:mm:ss.mmm`.
pub fn utc_string(t_ns: i64) -> String {
    let (y, m, d, hh, mm, ss, ms) = crate::fmt::utc_civil(t_ns);
    format!("{y:04}-{m:02}-{d:02} {hh:02}:{mm:02}:{ss:02}.{ms:03}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utc_dates() {
        assert_eq!(utc_string(0), "1970-01-01 00:00:00.000");
        // truth: 2026-11-20T07:42:13.118+01:00
        assert_eq!(
            utc_string(1_795_156_933_118_000_000),
            "2026-11-20 06:42:13.118"
        );
        assert_eq!(
            utc_string(951_782_400_000_000_000),
            "2000-02-29 00:00:00.000"
        );
    }
}
