//! Bad input, generated: empty files, wrong magic, truncation anywhere, bad
//! chunk CRCs, corrupt lengths, unknown compression and encodings, missing
//! and misnamed channels and fields, NaN / null / ±Infinity samples,
//! duplicated timestamps, time going backwards, gaps, malformed JSON, a
//! block on a scalar channel, oversized records, cancellation — and a
//! property test that flips and cuts bytes of a real log. Nothing panics;
//! every problem is a finding naming the file, the channel and the place,
//! and what can be read still loads.

use pinsight::model::Params;
use pinsight::progress::Progress;
use pinsight::rig::mcap_read::Source;
use pinsight::rig::synth::{self, Dropout, IdealTruth, SynthConfig, SynthLog, WriteSettings};
use pinsight::rig::{
    FindingCode, LoadOptions, LoadStatus, LogError, RigLog, Severity, SignalKind, load_source,
};
use proptest::prelude::*;
use std::io::Cursor;

fn cfg() -> SynthConfig {
    SynthConfig {
        revolutions: 3.3,
        ..SynthConfig::default()
    }
}

fn make(c: &SynthConfig) -> SynthLog {
    synth::generate(c, &IdealTruth::from_params(&Params::paper()))
}

fn bytes(log: &SynthLog, settings: &WriteSettings) -> Vec<u8> {
    let mut cur = Cursor::new(Vec::new());
    synth::write(log, &mut cur, settings).unwrap();
    cur.into_inner()
}

fn load_bytes(name: &str, b: Vec<u8>) -> Result<RigLog, LogError> {
    load_source(
        &Source::from_vec(name, b),
        &LoadOptions::default(),
        &Progress::hidden(),
    )
}

fn uncompressed() -> WriteSettings {
    WriteSettings {
        compression: None,
        chunk_size: 16 * 1024,
        ..WriteSettings::default()
    }
}

fn small_chunks() -> WriteSettings {
    WriteSettings {
        chunk_size: 16 * 1024,
        ..WriteSettings::default()
    }
}

fn count(log: &SynthLog, topic: &str) -> u64 {
    let c = log.channel_index(topic).unwrap();
    log.messages.iter().filter(|m| m.channel == c).count() as u64
}

fn findings(l: &RigLog, code: FindingCode) -> Vec<String> {
    l.report
        .with_code(code)
        .map(|f| f.message.clone())
        .collect()
}

#[test]
fn a_clean_synthetic_log_loads_ok() {
    let log = make(&cfg());
    for settings in [
        WriteSettings::default(),
        uncompressed(),
        WriteSettings {
            compression: Some(mcap::Compression::Lz4),
            ..small_chunks()
        },
        WriteSettings {
            chunked: false,
            ..WriteSettings::default()
        },
    ] {
        let l = load_bytes("clean.mcap", bytes(&log, &settings)).unwrap();
        assert_eq!(l.report.status, LoadStatus::Ok, "{:#?}", l.report.findings);
        assert_eq!(
            l.stats_of(SignalKind::Force).unwrap().samples,
            count(&log, "/rig/force")
        );
        assert_eq!(l.report.counts.messages, log.messages.len() as u64);
    }
}

#[test]
fn empty_wrong_magic_and_magic_only() {
    let e = load_bytes("empty.mcap", vec![]).unwrap_err();
    assert!(matches!(e, LogError::Empty { .. }));
    assert!(e.to_string().contains("empty.mcap"));
    let e = load_bytes("photo.mcap", b"\xFF\xD8\xFF\xE0 JFIF".to_vec()).unwrap_err();
    assert!(
        e.to_string().contains("photo.mcap") && e.to_string().contains("FF D8 FF E0"),
        "{e}"
    );
    let e = load_bytes("cut.mcap", b"\x89MC".to_vec()).unwrap_err();
    assert!(e.to_string().contains("inside the MCAP magic"));
    let l = load_bytes("magic.mcap", b"\x89MCAP0\r\n".to_vec()).unwrap();
    assert_eq!(l.report.status, LoadStatus::Error);
    assert!(l.report.has(FindingCode::Truncated));
}

#[test]
fn truncation_anywhere_recovers_what_is_before_the_break() {
    let log = make(&cfg());
    for settings in [
        small_chunks(),
        uncompressed(),
        WriteSettings {
            chunked: false,
            ..WriteSettings::default()
        },
    ] {
        let full = bytes(&log, &settings);
        let total = log.messages.len() as u64;
        let mut last = 0;
        for frac in [0.05, 0.2, 0.37, 0.5, 0.63, 0.8, 0.95, 0.999] {
            let cut = (full.len() as f64 * frac) as usize;
            let l = load_bytes("cut.mcap", full[..cut].to_vec()).unwrap();
            let got = l.report.counts.messages;
            assert!(got <= total);
            assert!(got >= last, "a longer prefix never yields fewer messages");
            last = got;
            let t: Vec<_> = l.report.with_code(FindingCode::Truncated).collect();
            assert_eq!(t.len(), 1, "{:#?}", l.report.findings);
            assert!(
                t[0].message.contains(&format!("byte {cut}")),
                "{}",
                t[0].message
            );
            assert!(t[0].place.as_ref().unwrap().byte_offset.is_some());
            if got == total {
                // Cut in the summary section: every message is there, the summary is lost.
                assert!(t[0].message.contains("summary section"));
                assert_eq!(l.report.status, LoadStatus::OkWithWarnings);
            } else {
                assert!(matches!(
                    l.report.status,
                    LoadStatus::Partial | LoadStatus::Error
                ));
            }
            // Every recovered sample is a true one: times are a prefix of the full log.
            if let Some(f) = l.signals.get(SignalKind::Force) {
                let c = log.channel_index("/rig/force").unwrap();
                let want: Vec<i64> = log
                    .messages
                    .iter()
                    .filter(|m| m.channel == c)
                    .map(|m| m.log_time as i64)
                    .take(f.len())
                    .collect();
                assert_eq!(f.t_ns, want);
            }
        }
        // Unchunked: every message record before the cut is recovered.
        if !settings.chunked {
            let cut = full.len() / 2;
            let l = load_bytes("cut.mcap", full[..cut].to_vec()).unwrap();
            assert!(l.report.counts.messages as f64 > 0.45 * total as f64);
        }
    }
}

#[test]
fn cut_inside_a_compressed_chunk_recovers_its_first_messages() {
    // zstd hands out whole blocks (≤ 128 KiB): a chunk of several blocks.
    let log = make(&SynthConfig {
        revolutions: 20.0,
        ..cfg()
    });
    let full = bytes(
        &log,
        &WriteSettings {
            chunk_size: 1 << 30,
            ..WriteSettings::default()
        },
    );
    // One big chunk: cut in its middle.
    let (off, len) = chunk_offsets(&full)[0];
    let l = load_bytes("one-chunk.mcap", full[..(off + len / 2) as usize].to_vec()).unwrap();
    assert!(
        l.report.has(FindingCode::PartialChunkRecovered),
        "{:#?}",
        l.report.findings
    );
    assert!(l.report.counts.messages > 0);
    assert_eq!(l.report.status, LoadStatus::Partial);
}

/// Offsets of the chunk records of a file (via the reader's own scan of a clean file).
fn chunk_offsets(b: &[u8]) -> Vec<(u64, u64)> {
    let s = pinsight::rig::mcap_read::scan(&Source::from_vec("x", b.to_vec()), &Default::default())
        .unwrap();
    s.items.iter().map(|i| (i.offset, i.len)).collect()
}

#[test]
fn bad_chunk_crc_drops_that_chunk_only() {
    let log = make(&cfg());
    let mut b = bytes(&log, &uncompressed());
    let chunks = chunk_offsets(&b);
    assert!(chunks.len() > 4);
    let (off, len) = chunks[2];
    // Flip a digit inside the chunk's records (a message payload).
    let p = (off + len / 2) as usize;
    let i = (p..p + 200).find(|&i| b[i].is_ascii_digit()).unwrap();
    b[i] = if b[i] == b'5' { b'6' } else { b'5' };
    let l = load_bytes("crc.mcap", b).unwrap();
    let f: Vec<_> = l.report.with_code(FindingCode::BadChunkCrc).collect();
    assert_eq!(f.len(), 1);
    assert!(
        f[0].message.contains(&format!("chunk at byte {off}")) && f[0].message.contains("crc.mcap")
    );
    assert_eq!(l.report.status, LoadStatus::Partial);
    assert_eq!(l.report.counts.chunks_failed, 1);
    assert!(l.report.counts.messages < log.messages.len() as u64);
    assert!(l.report.counts.messages > log.messages.len() as u64 / 2);
}

#[test]
fn corrupt_chunk_length_resyncs_on_the_next_chunk() {
    let log = make(&cfg());
    let clean = bytes(&log, &small_chunks());
    let chunks = chunk_offsets(&clean);
    let (off, _) = chunks[1];
    for with_summary in [true, false] {
        let mut b = clean.clone();
        b[off as usize + 8] = 0x7F; // the top byte of the record length
        if !with_summary {
            // Cut the end off too: no footer, no summary, the walk must search.
            b.truncate(chunks[chunks.len() - 1].0 as usize + 10);
        }
        let l = load_bytes("len.mcap", b).unwrap();
        let f: Vec<_> = l.report.with_code(FindingCode::CorruptRecord).collect();
        assert_eq!(f.len(), 1, "{:#?}", l.report.findings);
        assert!(f[0].message.contains(&format!("byte {off}")) && f[0].message.contains("resumes"));
        assert!(l.report.counts.chunks_read >= chunks.len() as u64 - 2);
    }
}

#[test]
fn unknown_compression_is_reported_per_chunk() {
    let log = make(&cfg());
    let mut b = bytes(&log, &small_chunks());
    // Rename the compression of the first chunk header: "zstd" → "brot".
    let pos = b.windows(4).position(|w| w == b"zstd").unwrap();
    b[pos..pos + 4].copy_from_slice(b"brot");
    let l = load_bytes("brot.mcap", b).unwrap();
    let f = findings(&l, FindingCode::UnknownCompression);
    assert_eq!(f.len(), 1);
    assert!(f[0].contains("'brot'"));
    assert_eq!(l.report.status, LoadStatus::Partial);
    assert!(l.report.counts.messages > 0);
}

#[test]
fn unknown_message_encoding_missing_and_misnamed_channels() {
    let mut log = make(&cfg());
    let f = log.channel_index("/rig/force").unwrap();
    // cdr and protobuf are decoded since issue 17; cbor is still unknown.
    log.channels[f].message_encoding = "cbor".into();
    let d = log.channel_index("/rig/displacement").unwrap();
    log.channels[d].topic = "/rig/displacment".into();
    let l = load_bytes("enc.mcap", bytes(&log, &WriteSettings::default())).unwrap();
    assert_eq!(l.report.status, LoadStatus::OkWithWarnings);
    let enc = findings(&l, FindingCode::UnknownEncoding);
    assert_eq!(enc.len(), 1);
    assert!(
        enc[0].contains("enc.mcap: /rig/force (force)") && enc[0].contains("'cbor'"),
        "{}",
        enc[0]
    );
    let miss = findings(&l, FindingCode::MissingChannel);
    assert_eq!(miss.len(), 1);
    assert!(miss[0].contains("/rig/displacement") && miss[0].contains("/rig/displacment"));
    assert!(l.report.has(FindingCode::UnusedChannel));
    let samples = |s: &Option<pinsight::rig::signals::Signal>| s.as_ref().map_or(0, |s| s.len());
    assert_eq!(samples(&l.signals.force), 0);
    assert_eq!(samples(&l.signals.displacement), 0);
    assert_eq!(
        l.stats_of(SignalKind::Angle).unwrap().samples,
        count(&log, "/rig/spindle")
    );
    assert!(l.signals.cycle.is_some());
}

#[test]
fn misnamed_field_and_malformed_json() {
    let mut log = make(&cfg());
    let f = log.channel_index("/rig/force").unwrap();
    let d = log.channel_index("/rig/displacement").unwrap();
    let mut nf = 0;
    for m in log.messages.iter_mut().filter(|m| m.channel == f).take(7) {
        m.data = br#"{"force": 1.0}"#.to_vec();
        nf += 1;
    }
    let t_bad = log
        .messages
        .iter()
        .find(|m| m.channel == d)
        .unwrap()
        .log_time;
    for m in log.messages.iter_mut().filter(|m| m.channel == d).take(3) {
        m.data = br#"{"displacement_mm": 1.0"#.to_vec();
    }
    let l = load_bytes("fields.mcap", bytes(&log, &WriteSettings::default())).unwrap();
    let st = l.stats_of(SignalKind::Force).unwrap();
    assert_eq!(st.missing_field, nf);
    let mf = findings(&l, FindingCode::MissingField);
    assert!(mf[0].contains("7 of") && mf[0].contains("'force_n'") && mf[0].contains("/rig/force"));
    let bad = findings(&l, FindingCode::MalformedMessage);
    assert!(
        bad[0].contains("3 message(s) are not valid JSON") && bad[0].contains(&t_bad.to_string()),
        "{}",
        bad[0]
    );
    assert_eq!(l.report.status, LoadStatus::OkWithWarnings);
}

#[test]
fn nan_null_infinite_and_non_numeric_samples() {
    let mut log = make(&cfg());
    let d = log.channel_index("/rig/displacement").unwrap();
    let tokens: [&[u8]; 6] = [
        b"NaN",
        b"null",
        b"Infinity",
        b"-Infinity",
        b"1e999",
        b"\"abc\"",
    ];
    let idx: Vec<usize> = log
        .messages
        .iter()
        .enumerate()
        .filter(|(_, m)| m.channel == d)
        .map(|(i, _)| i)
        .skip(100)
        .step_by(37)
        .take(6)
        .collect();
    let mut times = Vec::new();
    for (k, &i) in idx.iter().enumerate() {
        let mut p = br#"{"displacement_mm": "#.to_vec();
        p.extend_from_slice(tokens[k]);
        p.push(b'}');
        log.messages[i].data = p;
        times.push(log.messages[i].log_time as i64);
    }
    let l = load_bytes("nan.mcap", bytes(&log, &WriteSettings::default())).unwrap();
    let st = l.stats_of(SignalKind::Displacement).unwrap();
    assert_eq!(
        (
            st.invalid.nan_token,
            st.invalid.null,
            st.invalid.non_finite,
            st.invalid.not_number
        ),
        (1, 1, 3, 1)
    );
    assert_eq!(
        st.invalid_times.iter().map(|x| x.0).collect::<Vec<_>>(),
        times
    );
    assert_eq!(st.samples, count(&log, "/rig/displacement") - 6);
    assert_eq!(st.gap_count, 0, "an invalid sample is not a gap");
    let sig = l.signals.displacement.as_ref().unwrap();
    assert!(sig.values.iter().all(|v| v.is_finite()));
    let f = findings(&l, FindingCode::InvalidSamples);
    assert!(
        f[0].contains("nan.mcap: /rig/displacement (displacement): 6 invalid")
            && f[0].contains(&times[0].to_string())
    );
}

#[test]
fn duplicates_backward_time_and_gaps() {
    let c = SynthConfig {
        dropouts: vec![Dropout {
            signal: SignalKind::Force,
            from_s: 0.05,
            to_s: 0.06,
        }],
        ..cfg()
    };
    let mut log = make(&c);
    let f = log.channel_index("/rig/force").unwrap();
    let s = log.channel_index("/rig/spindle").unwrap();
    // Three exact duplicates of force messages.
    let dups: Vec<usize> = log
        .messages
        .iter()
        .enumerate()
        .filter(|(_, m)| m.channel == f)
        .map(|(i, _)| i)
        .skip(50)
        .step_by(100)
        .take(3)
        .collect();
    for &i in dups.iter().rev() {
        let m = log.messages[i].clone();
        log.messages.insert(i + 1, m);
    }
    // The spindle clock steps back 3 ms at its 400th message.
    let sp: Vec<usize> = log
        .messages
        .iter()
        .enumerate()
        .filter(|(_, m)| m.channel == s)
        .map(|(i, _)| i)
        .collect();
    let prev_t = log.messages[sp[399]].log_time as i64;
    for &i in &sp[400..] {
        log.messages[i].log_time -= 3_000_000;
    }
    let jump_t = log.messages[sp[400]].log_time as i64;
    let l = load_bytes("faults.mcap", bytes(&log, &WriteSettings::default())).unwrap();
    assert_eq!(l.report.status, LoadStatus::OkWithWarnings);
    let fs = l.stats_of(SignalKind::Force).unwrap();
    assert_eq!((fs.duplicates, fs.identical_duplicates), (3, 3));
    let big: Vec<_> = fs.gaps.iter().filter(|g| g.missing_samples > 2).collect();
    assert_eq!(big.len(), 1);
    assert!(
        (big[0].duration_s - 0.0101).abs() < 2e-4,
        "{}",
        big[0].duration_s
    );
    assert!((big[0].missing_samples as i64 - 100).abs() <= 1);
    let gap = findings(&l, FindingCode::Gap);
    assert!(
        gap.iter()
            .any(|m| m.contains("faults.mcap: /rig/force (force): gap of 10."))
    );
    let ss = l.stats_of(SignalKind::Angle).unwrap();
    assert_eq!(ss.backward_steps, 1);
    assert_eq!(
        (ss.backward[0].previous_ns, ss.backward[0].log_time_ns),
        (prev_t, jump_t)
    );
    assert!((ss.backward[0].jump_s + 0.003).abs() < 1e-9);
    assert_eq!(ss.duplicates, 15, "3 ms at 5 kHz overlap");
    let back = findings(&l, FindingCode::TimeBackwards);
    assert!(back[0].contains("jumps back by 3.000 ms") && back[0].contains(&jump_t.to_string()));
}

#[test]
fn a_block_on_a_scalar_channel_is_not_read_as_a_scalar() {
    let mut log = make(&cfg());
    let f = log.channel_index("/rig/force").unwrap();
    let i = log.messages.iter().position(|m| m.channel == f).unwrap();
    let t = log.messages[i].log_time;
    log.messages[i].data =
        format!(r#"{{"t0_ns": {t}, "dt_ns": 100000, "values": [1.0, 2.0, 3.0]}}"#).into_bytes();
    let l = load_bytes("shape.mcap", bytes(&log, &WriteSettings::default())).unwrap();
    let st = l.stats_of(SignalKind::Force).unwrap();
    assert_eq!(st.wrong_shape, 1);
    assert_eq!(st.samples, count(&log, "/rig/force") - 1);
    assert!(findings(&l, FindingCode::WrongShape)[0].contains("not read as a scalar"));
}

#[test]
fn blocks_round_trip() {
    let c = SynthConfig {
        blocks: true,
        block_len: 64,
        ..cfg()
    };
    let scalar = make(&cfg());
    let log = make(&c);
    let l = load_bytes("blocks.mcap", bytes(&log, &WriteSettings::default())).unwrap();
    assert_eq!(l.report.status, LoadStatus::Ok, "{:#?}", l.report.findings);
    let sl = load_bytes("scalar.mcap", bytes(&scalar, &WriteSettings::default())).unwrap();
    let (a, b) = (
        l.signals.force.as_ref().unwrap(),
        sl.signals.force.as_ref().unwrap(),
    );
    assert_eq!(a.t_ns, b.t_ns);
    assert_eq!(a.values, b.values);
}

#[test]
fn oversized_records_and_bad_metadata() {
    let mut log = make(&cfg());
    log.metadata[0]
        .1
        .insert("clearance_mm".into(), "zero point one".into());
    log.attachments.push((
        "big.bin".into(),
        "application/octet-stream".into(),
        vec![7u8; 100_000],
    ));
    let b = bytes(&log, &WriteSettings::default());
    let opts = LoadOptions {
        read: pinsight::rig::ReadOptions {
            record_length_limit: 50_000,
            ..Default::default()
        },
        ..Default::default()
    };
    let l = load_source(&Source::from_vec("big.mcap", b), &opts, &Progress::hidden()).unwrap();
    let f = findings(&l, FindingCode::RecordTooLarge);
    assert!(
        f.iter()
            .any(|m| m.contains("attachment record") && m.contains("limit of 50000"))
    );
    assert!(findings(&l, FindingCode::Metadata)[0].contains("clearance_mm = 'zero point one'"));
    assert_eq!(l.meta.clearance_mm, None);
}

#[test]
fn cancelled_load_keeps_what_it_has() {
    let log = make(&cfg());
    let p = Progress::new(0);
    p.cancel();
    let l = load_source(
        &Source::from_vec("c.mcap", bytes(&log, &small_chunks())),
        &LoadOptions::default(),
        &p,
    )
    .unwrap();
    assert!(l.report.has(FindingCode::Cancelled));
    assert!(
        l.report
            .findings
            .iter()
            .any(|f| f.severity >= Severity::DataLoss)
    );
}

fn fixture_bytes() -> &'static [u8] {
    static B: std::sync::OnceLock<Vec<u8>> = std::sync::OnceLock::new();
    B.get_or_init(|| {
        let c = SynthConfig {
            revolutions: 1.5,
            ..SynthConfig::default()
        };
        bytes(
            &make(&c),
            &WriteSettings {
                chunk_size: 8 * 1024,
                ..WriteSettings::default()
            },
        )
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]
    /// Flipped bytes and cuts never panic and give either a log or a clear error.
    #[test]
    fn flips_and_cuts_never_panic(flips in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 0..12),
                                   cut in prop::option::of(any::<prop::sample::Index>()),
                                   uncompressed_input in any::<bool>()) {
        let mut b = if uncompressed_input {
            let c = SynthConfig { revolutions: 1.0, ..SynthConfig::default() };
            bytes(&make(&c), &WriteSettings { compression: None, chunk_size: 8 * 1024, ..WriteSettings::default() })
        } else {
            fixture_bytes().to_vec()
        };
        for (i, x) in flips {
            let i = i.index(b.len());
            b[i] ^= x.max(1);
        }
        if let Some(c) = cut {
            b.truncate(c.index(b.len() + 1));
        }
        match load_bytes("fuzz.mcap", b) {
            Ok(l) => {
                prop_assert!(l.report.findings.iter().all(|f| f.message.starts_with("fuzz.mcap")));
                let _ = pinsight::rig::cycles::analyse(&l, &Default::default());
            }
            Err(e) => prop_assert!(e.to_string().contains("fuzz.mcap")),
        }
    }
}

/// Issue 17's bad binary input: a protobuf schema that does not parse, CDR
/// messages that do not match their ros2msg schema, and an encoding pinsight
/// does not read. Each is a finding naming the channel and the place; the
/// rest of the log still loads.
#[test]
fn bad_schemas_messages_and_encodings_are_findings_and_the_rest_loads() {
    let mut log = make(&cfg());
    let ch = |log: &SynthLog, topic: &str| log.channel_index(topic).unwrap();
    let force = ch(&log, "/rig/force");
    log.channels[force].schema_encoding = "protobuf".into();
    log.channels[force].message_encoding = "protobuf".into();
    log.channels[force].schema = "not a FileDescriptorSet".into();
    let disp = ch(&log, "/rig/displacement");
    log.channels[disp].schema_encoding = "ros2msg".into();
    log.channels[disp].message_encoding = "cdr".into();
    log.channels[disp].schema = "float64 displacement_mm\n".into();
    let mut first_disp = None;
    for m in log.messages.iter_mut().filter(|m| m.channel == disp) {
        // Little-endian CDR with 6 of the 8 bytes of the float64.
        m.data = vec![0, 1, 0, 0, 1, 2, 3, 4, 5, 6];
        first_disp.get_or_insert(m.log_time);
    }
    let cyc = ch(&log, "/rig/cycle");
    log.channels[cyc].message_encoding = "flatbuffer".into();
    let l = load_bytes("bad-enc.mcap", bytes(&log, &small_chunks())).unwrap();

    let unknown = findings(&l, FindingCode::UnknownEncoding);
    let about = |topic: &str| {
        unknown
            .iter()
            .find(|f| f.contains(topic))
            .unwrap_or_else(|| panic!("no finding about {topic}: {unknown:?}"))
            .clone()
    };
    assert!(about("/rig/force").contains("not a valid FileDescriptorSet"));
    assert!(about("/rig/cycle").contains("'flatbuffer'"));
    let bad = findings(&l, FindingCode::MalformedMessage);
    assert_eq!(bad.len(), 1, "{bad:?}");
    assert!(
        bad[0].contains("/rig/displacement")
            && bad[0].contains("do not decode against the channel's schema")
            && bad[0].contains("does not match its schema"),
        "{}",
        bad[0]
    );
    // The spindle is untouched: angle and speed load in full, and cycles
    // come from the angle.
    assert_eq!(
        l.signals.angle.as_ref().unwrap().len() as u64,
        count(&log, "/rig/spindle")
    );
    let samples = |s: &Option<pinsight::rig::signals::Signal>| s.as_ref().map_or(0, |s| s.len());
    assert_eq!(samples(&l.signals.force), 0);
    assert_eq!(samples(&l.signals.displacement), 0);
    let cs = pinsight::rig::analyse(&l, &pinsight::rig::CycleOptions::default());
    assert!(cs.cycles.len() >= 2, "{}", cs.cycles.len());
}
