//! The protobuf and ROS 2 twins of every interop log (fixtures/twins,
//! written by the official Python writers `mcap-protobuf-support` and
//! `mcap-ros2-support` with `write_twins.py`, not by pinsight) load with the
//! same signals, cycles, overlay figures and images as their JSON originals
//! (issue 17). Protobuf carries the JSON values bit for bit, so it must agree
//! exactly; the ROS 2 twin sends the spindle speed in rad/s (JointState
//! velocity), converted back to rpm, so its figures agree to a few ulps.

use serde_json::Value;
use std::path::Path;
use std::process::Command;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn logs() -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(root().join("fixtures/interop/logs"))
        .unwrap()
        .filter_map(|e| {
            let n = e.unwrap().file_name().into_string().unwrap();
            n.strip_suffix(".mcap").map(str::to_string)
        })
        .collect();
    v.sort();
    assert_eq!(v.len(), 11, "every interop log has its twins");
    v
}

/// `pinsight ARGS --json` as JSON.
fn run(args: &[&str]) -> Value {
    let mut a = args.to_vec();
    a.push("--json");
    run_raw(&a)
}

/// `pinsight ARGS`, whose output is JSON.
fn run_raw(args: &[&str]) -> Value {
    let out = Command::new(env!("CARGO_BIN_EXE_pinsight"))
        .args(args)
        .current_dir(root())
        .output()
        .unwrap();
    assert!(
        out.status.code().is_some_and(|c| c <= 1),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("{args:?}: {e}"))
}

/// The three files of one log, with the channel-map arguments of each.
fn variants(name: &str) -> [(String, Vec<String>); 3] {
    let json_map = format!("fixtures/interop/logs/{name}.channels.toml");
    let map = |m: &str| vec!["--channels".to_string(), m.to_string()];
    let jm = if root().join(&json_map).exists() {
        map(&json_map)
    } else {
        vec![]
    };
    [
        (format!("fixtures/interop/logs/{name}.mcap"), jm.clone()),
        (format!("fixtures/twins/{name}.pb.mcap"), jm),
        (
            format!("fixtures/twins/{name}.ros2.mcap"),
            map(&format!("fixtures/twins/{name}.ros2.channels.toml")),
        ),
    ]
}

/// Largest relative difference between the numbers of two JSON values of
/// the same shape (strings and shapes must match; `file` and the timing
/// `wall_ms` are skipped).
fn max_rel_diff(a: &Value, b: &Value, at: &str) -> f64 {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            if x == y {
                0.0
            } else {
                (x - y).abs() / x.abs().max(y.abs())
            }
        }
        (Value::Array(x), Value::Array(y)) => {
            assert_eq!(x.len(), y.len(), "{at}: lengths");
            x.iter()
                .zip(y)
                .enumerate()
                .map(|(i, (p, q))| max_rel_diff(p, q, &format!("{at}[{i}]")))
                .fold(0.0, f64::max)
        }
        (Value::Object(x), Value::Object(y)) => {
            let mut m = 0.0f64;
            for (k, v) in x {
                if k == "file" || k == "wall_ms" {
                    continue;
                }
                let w = y.get(k).unwrap_or_else(|| panic!("{at}.{k} missing"));
                m = m.max(max_rel_diff(v, w, &format!("{at}.{k}")));
            }
            m
        }
        _ => {
            assert_eq!(a, b, "{at}");
            0.0
        }
    }
}

fn check(name: &str, what: &str, pick: impl Fn(&Value) -> Value, args: &[&str]) {
    let [json, pb, ros] = variants(name);
    let get = |(file, map): &(String, Vec<String>)| {
        let mut a: Vec<&str> = args.to_vec();
        a.push(file);
        a.extend(map.iter().map(String::as_str));
        pick(&run(&a))
    };
    let (j, p, r) = (get(&json), get(&pb), get(&ros));
    let dp = max_rel_diff(&j, &p, what);
    let dr = max_rel_diff(&j, &r, what);
    assert_eq!(dp, 0.0, "{name} protobuf twin: {what} differ");
    assert!(dr < 1e-12, "{name} ROS 2 twin: {what} differ by {dr:e}");
}

/// Signal facts that do not depend on the encoding (a JSON `null` is an
/// absent protobuf field and a NaN in CDR, so the invalid-sample counts
/// differ by kind, not the samples kept).
fn signal_facts(v: &Value) -> Value {
    let sigs = v["signals"].as_array().unwrap();
    Value::Array(
        sigs.iter()
            .map(|s| {
                serde_json::json!({
                    "kind": s["kind"], "topic": s["topic"], "messages": s["messages"],
                    "blocks": s["blocks"], "samples": s["samples"], "first_ns": s["first_ns"],
                    "last_ns": s["last_ns"], "duplicates": s["duplicates"],
                    "gap_count": s["gap_count"], "out_of_order": s["out_of_order"],
                })
            })
            .collect(),
    )
}

#[test]
fn twins_give_the_same_signals_and_cycles() {
    for name in logs() {
        check(&name, "log signals", signal_facts, &["log", "--all-cycles"]);
        check(
            &name,
            "cycles",
            |v| v["cycles"].clone(),
            &["log", "--all-cycles"],
        );
    }
}

#[test]
fn twins_give_the_same_overlay_figures() {
    for name in logs() {
        check(
            &name,
            "overlay",
            |v| {
                let mut v = v.clone();
                v.as_object_mut().unwrap().remove("params_notes");
                v
            },
            &["overlay"],
        );
    }
}

#[test]
fn twins_carry_the_same_images() {
    use pinsight::rig::images::read_images;
    let name = "run-2000-images";
    let [json, pb, ros] = variants(name);
    let (_, a) = read_images(&root().join(&json.0)).unwrap();
    assert_eq!(a.len(), 10);
    for twin in [pb, ros] {
        let (_, b) = read_images(&root().join(&twin.0)).unwrap();
        assert_eq!(a.len(), b.len(), "{}", twin.0);
        for (x, y) in a.iter().zip(&b) {
            assert_eq!(
                (x.cycle, x.log_time_ns, &x.frame_id, &x.format, &x.data),
                (y.cycle, y.log_time_ns, &y.frame_id, &y.format, &y.data),
                "{}",
                twin.0
            );
        }
    }
}

/// The TUI's path (the engine lists a log's images and decodes each on
/// demand, by its codec): the Yield pane rendered headless gives the same
/// report for the JSON log and its twins.
#[test]
fn twins_give_the_same_yield_pane() {
    let [json, pb, ros] = variants("run-2000-images");
    let recipe = "fixtures/interop/images/hdr-2x10.toml";
    let pane = |file: &str| {
        let v = run_raw(&["render", "yield", file, recipe, "--format", "json"]);
        let r = &v["report"];
        assert_eq!(r["items"], 10, "{file}");
        serde_json::json!([
            r["passed"],
            r["failed"],
            r["errors"],
            r["dppm"],
            r["pins_inspected"]
        ])
    };
    let expected = pane(&json.0);
    assert_eq!(pane(&pb.0), expected);
    assert_eq!(pane(&ros.0), expected);
}
