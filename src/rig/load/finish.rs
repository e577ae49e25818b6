//! Two stages of [`super::load_inner`]: the run's `rig` metadata, and
//! finishing the decoded signals with their findings.

use super::{LoadOptions, Signals, State};
use crate::rig::channel_map::SignalKind;
use crate::rig::mcap_read::MetadataRecord;
use crate::rig::meta::RigMeta;
use crate::rig::report::{Finding, FindingCode, Place, Severity};
use crate::rig::signals::{self, SignalStats};
use rayon::prelude::*;
use std::collections::{BTreeMap, BTreeSet};

/// The run's `rig` metadata: every record named `rig` merged (later values
/// win, with a warning), typed, then the user's `--meta` overrides; a log
/// without one gets an info finding.
pub(super) fn rig_metadata(
    metadata: &[MetadataRecord],
    opts: &LoadOptions,
    file: &str,
    findings: &mut Vec<Finding>,
) -> RigMeta {
    // Metadata.
    let rig_records: Vec<_> = metadata.iter().filter(|m| m.name == "rig").collect();
    let mut raw = BTreeMap::new();
    for m in &rig_records {
        raw.extend(m.map.clone());
    }
    if rig_records.len() > 1 {
        findings.push(Finding::new(
            Severity::Warning,
            FindingCode::Metadata,
            file,
            None,
            Some(Place::byte(rig_records[1].offset)),
            format!(
                "{} metadata records named 'rig'; merged, later values win",
                rig_records.len()
            ),
        ));
    }
    let mut meta = RigMeta::from_raw(raw, file, findings);
    meta.present = !rig_records.is_empty();
    let meta = meta.apply_overrides(&opts.meta_overrides, file, findings);
    if !meta.present {
        findings.push(Finding::new(
            Severity::Info,
            FindingCode::MetadataMissing,
            file,
            None,
            None,
            "no metadata record named 'rig': nominal clearance, speed, standoff etc. must come from the session",
        ));
    }

    meta
}

/// Finishes every decoded signal (in parallel: they are independent) and
/// moves their findings into the log's, reporting the time-stream findings
/// of signals sharing a topic once.
pub(super) fn finish_signals(
    st: &mut State,
    file: &str,
    span: Option<(i64, i64)>,
) -> (Signals, Vec<SignalStats>) {
    // Finish the signals.
    let mut sigs = Signals::default();
    let mut sig_stats = Vec::new();
    let mut sig_findings: Vec<(SignalKind, String, Vec<Finding>)> = Vec::new();
    // Signals are independent: finish them in parallel.
    let pending: Vec<_> = std::mem::take(&mut st.sigs).into_iter().collect();
    let finished: Vec<_> = pending
        .into_par_iter()
        .map(|(kind, (topic, field, buf))| {
            let r = signals::finish(kind, &topic, &field, buf, file, span);
            (kind, topic, r)
        })
        .collect();
    for (kind, topic, (s, stt, f)) in finished {
        sig_findings.push((kind, topic, f));
        sig_stats.push(stt);
        *sigs.slot(kind) = Some(s);
    }
    // Time-stream findings of signals sharing a topic are reported once.
    let time_codes = [
        FindingCode::OutOfOrder,
        FindingCode::TimeBackwards,
        FindingCode::DuplicateTimestamps,
        FindingCode::Gap,
        FindingCode::EmptyChannel,
        FindingCode::MalformedMessage,
    ];
    let mut topic_kinds: BTreeMap<String, Vec<SignalKind>> = BTreeMap::new();
    for (k, t, _) in &sig_findings {
        topic_kinds.entry(t.clone()).or_default().push(*k);
    }
    let mut done_topics = BTreeSet::new();
    for (kind, topic, fs) in sig_findings {
        let kinds = &topic_kinds[&topic];
        let first = done_topics.insert(topic.clone());
        let own = format!("{topic} ({})", kind.name());
        let group = format!(
            "{topic} ({})",
            kinds
                .iter()
                .map(|k| k.name())
                .collect::<Vec<_>>()
                .join(", ")
        );
        for mut f in fs {
            if time_codes.contains(&f.code) {
                if !first {
                    continue;
                }
                if kinds.len() > 1 {
                    f.message = f.message.replacen(&own, &group, 1);
                    f.channel = Some(group.clone());
                }
            }
            st.findings.push(f);
        }
    }

    (sigs, sig_stats)
}
