//! Hive-style partition folders: `images/part=HDR-2x10/lot=L42/data.parquet`.
//!
//! The convention of Hive and Spark, which DuckDB (`hive_partitioning`),
//! pyarrow (`partitioning="hive"`) and polars read: one folder level per
//! partition column, named `column=value`; the partition columns are not
//! stored in the files (the folder names carry them); a missing value is
//! `__HIVE_DEFAULT_PARTITION__`; characters a path cannot carry are
//! escaped `%XX` as Hive's `escapePathName` does. Folders and files are
//! written in sorted order, rows inside a file in the table's order.

use super::table::{ParquetError, read_file};
use arrow_array::{Array, ArrayRef, RecordBatch, StringArray, UInt32Array};
use arrow_schema::{DataType, Schema, SchemaRef};
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

/// The folder name of a missing (or empty) partition value.
pub const DEFAULT_PARTITION: &str = "__HIVE_DEFAULT_PARTITION__";

/// A column a data set can be partitioned by.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PartitionKey {
    /// The part number.
    Part,
    Lot,
    Rig,
}

impl PartitionKey {
    pub const ALL: [PartitionKey; 3] = [PartitionKey::Part, PartitionKey::Lot, PartitionKey::Rig];

    /// The column (and folder) name.
    pub fn column(self) -> &'static str {
        match self {
            PartitionKey::Part => "part",
            PartitionKey::Lot => "lot",
            PartitionKey::Rig => "rig",
        }
    }
}

/// Parses `part,lot` (each at most once).
pub fn parse_partition_keys(s: &str) -> Result<Vec<PartitionKey>, String> {
    let mut keys = Vec::new();
    for w in s.split(',').map(str::trim).filter(|w| !w.is_empty()) {
        let k = PartitionKey::ALL
            .into_iter()
            .find(|k| k.column() == w)
            .ok_or_else(|| format!("partition key `{w}`: expected part, lot or rig"))?;
        if keys.contains(&k) {
            return Err(format!("partition key `{w}` given twice"));
        }
        keys.push(k);
    }
    if keys.is_empty() {
        return Err(format!("`{s}`: no partition key (part, lot, rig)"));
    }
    Ok(keys)
}

/// Hive's escaping of a path segment.
pub fn escape(v: &str) -> String {
    let mut s = String::with_capacity(v.len());
    for c in v.chars() {
        let special = matches!(
            c,
            '"' | '#'
                | '%'
                | '\''
                | '*'
                | '/'
                | ':'
                | '='
                | '?'
                | '\\'
                | '\u{7f}'
                | '{'
                | '['
                | ']'
                | '^'
        ) || (c as u32) < 0x20;
        if special {
            s.push_str(&format!("%{:02X}", c as u32));
        } else {
            s.push(c);
        }
    }
    s
}

/// The inverse of [`escape`] (a malformed `%` is kept as it stands).
pub fn unescape(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if b[i] == b'%'
            && i + 2 < b.len()
            && let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2]))
        {
            out.push((h * 16 + l) as u8);
            i += 3;
            continue;
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// A partition value as its folder segment.
fn segment(key: &str, v: Option<&str>) -> String {
    match v.filter(|v| !v.is_empty()) {
        Some(v) => format!("{key}={}", escape(v)),
        None => format!("{key}={DEFAULT_PARTITION}"),
    }
}

/// The table cut by `keys`: (relative folder `part=A/lot=B`, its rows
/// without the partition columns), folders sorted. Every key must be a
/// text column of the table.
pub fn partition(
    batch: &RecordBatch,
    keys: &[PartitionKey],
) -> Result<Vec<(String, RecordBatch)>, ParquetError> {
    let cols: Vec<&StringArray> = keys
        .iter()
        .map(|k| {
            batch
                .column_by_name(k.column())
                .and_then(|c| c.as_any().downcast_ref::<StringArray>())
                .ok_or_else(|| ParquetError::File {
                    path: k.column().into(),
                    message: "not a text column of the table".into(),
                })
        })
        .collect::<Result<_, _>>()?;
    let mut groups: BTreeMap<String, Vec<u32>> = BTreeMap::new();
    for row in 0..batch.num_rows() {
        let path: Vec<String> = keys
            .iter()
            .zip(&cols)
            .map(|(k, c)| segment(k.column(), (!c.is_null(row)).then(|| c.value(row))))
            .collect();
        groups.entry(path.join("/")).or_default().push(row as u32);
    }
    let keep: Vec<usize> = batch
        .schema()
        .fields()
        .iter()
        .enumerate()
        .filter(|(_, f)| !keys.iter().any(|k| k.column() == f.name()))
        .map(|(i, _)| i)
        .collect();
    let projected = batch.project(&keep)?;
    groups
        .into_iter()
        .map(|(path, rows)| {
            let idx = UInt32Array::from(rows);
            let t = arrow_select::take::take_record_batch(&projected, &idx)?;
            Ok((path, t))
        })
        .collect()
}

/// Every `*.parquet` file below `dir` with its folders relative to `dir`,
/// sorted by path.
fn parquet_files(dir: &Path, rel: &str, out: &mut Vec<(String, std::path::PathBuf)>) {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return;
    };
    let mut entries: Vec<_> = rd.flatten().map(|e| e.path()).collect();
    entries.sort();
    for p in entries {
        let name = p
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        if name.starts_with('.') {
            continue;
        }
        if p.is_dir() {
            let r = if rel.is_empty() {
                name
            } else {
                format!("{rel}/{name}")
            };
            parquet_files(&p, &r, out);
        } else if name.ends_with(".parquet") {
            out.push((rel.to_string(), p));
        }
    }
}

/// Reads a partitioned data set written by [`partition`] back into one
/// table of `schema` (the partition columns, text, restored from the
/// folder names). Files are read in path order.
pub fn read_partitioned(dir: &Path, schema: &SchemaRef) -> Result<RecordBatch, ParquetError> {
    let mut files = Vec::new();
    parquet_files(dir, "", &mut files);
    let batches = files
        .iter()
        .map(|(rel, path)| read_partition_file(path, rel, schema))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(arrow_select::concat::concat_batches(schema, &batches)?)
}

/// Reads one file of a partitioned data set, `rel` its folders below the
/// data set's root (`part=A/lot=B`): a table of `schema` with the
/// partition columns restored from the folder names.
pub fn read_partition_file(
    path: &Path,
    rel: &str,
    schema: &SchemaRef,
) -> Result<RecordBatch, ParquetError> {
    let err = |message: String| ParquetError::File {
        path: path.display().to_string(),
        message,
    };
    let mut values: BTreeMap<String, Option<String>> = BTreeMap::new();
    for seg in rel.split('/').filter(|s| !s.is_empty()) {
        let (k, v) = seg
            .split_once('=')
            .ok_or_else(|| err(format!("folder `{seg}` is not a partition (column=value)")))?;
        let v = (v != DEFAULT_PARTITION).then(|| unescape(v));
        values.insert(k.to_string(), v);
    }
    for k in values.keys() {
        match schema.field_with_name(k) {
            Ok(f) if *f.data_type() == DataType::Utf8 => {}
            _ => return Err(err(format!("partition `{k}` is not a text column"))),
        }
    }
    let file_schema = Arc::new(Schema::new(
        schema
            .fields()
            .iter()
            .filter(|f| !values.contains_key(f.name()))
            .cloned()
            .collect::<Vec<_>>(),
    ));
    let part = read_file(path, &file_schema)?;
    let n = part.num_rows();
    let cols: Vec<ArrayRef> = schema
        .fields()
        .iter()
        .map(|f| match values.get(f.name()) {
            Some(v) => Arc::new(StringArray::from(vec![v.as_deref(); n])) as ArrayRef,
            None => part
                .column_by_name(f.name())
                .cloned()
                .unwrap_or_else(|| arrow_array::new_null_array(f.data_type(), n)),
        })
        .collect();
    Ok(RecordBatch::try_new(schema.clone(), cols)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escaping_is_hives_and_round_trips() {
        assert_eq!(escape("HDR-2x10/2.54"), "HDR-2x10%2F2.54");
        assert_eq!(escape("a=b:c%"), "a%3Db%3Ac%25");
        assert_eq!(escape("L 42 é"), "L 42 é");
        for v in ["HDR-2x10/2.54", "a=b:c%", "x\ny", "100%", "%zz", "%4"] {
            assert_eq!(unescape(&escape(v)), v, "{v}");
        }
        assert_eq!(unescape("%zz"), "%zz");
        assert_eq!(segment("lot", None), "lot=__HIVE_DEFAULT_PARTITION__");
        assert_eq!(segment("lot", Some("")), "lot=__HIVE_DEFAULT_PARTITION__");
    }

    #[test]
    fn keys_parse_and_refuse() {
        assert_eq!(
            parse_partition_keys("part, lot").unwrap(),
            vec![PartitionKey::Part, PartitionKey::Lot]
        );
        assert!(parse_partition_keys("day").unwrap_err().contains("day"));
        assert!(
            parse_partition_keys("lot,lot")
                .unwrap_err()
                .contains("twice")
        );
        assert!(parse_partition_keys(",").is_err());
    }

    #[test]
    fn partitioned_and_read_back_is_the_table() {
        use arrow_array::UInt64Array;
        use arrow_schema::Field;
        let schema = Arc::new(Schema::new(vec![
            Field::new("item", DataType::UInt64, false),
            Field::new("part", DataType::Utf8, true),
            Field::new("lot", DataType::Utf8, true),
        ]));
        let lots = [Some("L1"), None, Some("a/b"), Some("L1"), Some("")];
        let t = RecordBatch::try_new(
            schema.clone(),
            vec![
                Arc::new(UInt64Array::from_iter_values(0..5)),
                Arc::new(StringArray::from(vec![Some("P"); 5])),
                Arc::new(StringArray::from(lots.to_vec())),
            ],
        )
        .unwrap();
        let parts = partition(&t, &[PartitionKey::Part, PartitionKey::Lot]).unwrap();
        let names: Vec<&str> = parts.iter().map(|(p, _)| p.as_str()).collect();
        assert_eq!(
            names,
            vec![
                "part=P/lot=L1",
                "part=P/lot=__HIVE_DEFAULT_PARTITION__",
                "part=P/lot=a%2Fb"
            ]
        );
        assert_eq!(parts[0].1.num_columns(), 1, "partition columns not stored");
        let d = tempfile::tempdir().unwrap();
        for (p, b) in &parts {
            let dir = d.path().join(p);
            std::fs::create_dir_all(&dir).unwrap();
            std::fs::write(
                dir.join("data.parquet"),
                super::super::write_table(b).unwrap(),
            )
            .unwrap();
        }
        let back = read_partitioned(d.path(), &schema).unwrap();
        // Rows come back by folder; sorted by item they are the table, the
        // empty lot read as missing (Hive's convention).
        let items = back
            .column(0)
            .as_any()
            .downcast_ref::<UInt64Array>()
            .unwrap();
        let lot = back
            .column(2)
            .as_any()
            .downcast_ref::<StringArray>()
            .unwrap();
        let mut rows: Vec<(u64, Option<String>)> = (0..5)
            .map(|i| {
                (
                    items.value(i),
                    (!lot.is_null(i)).then(|| lot.value(i).to_string()),
                )
            })
            .collect();
        rows.sort();
        assert_eq!(
            rows,
            vec![
                (0, Some("L1".into())),
                (1, None),
                (2, Some("a/b".into())),
                (3, Some("L1".into())),
                (4, None)
            ]
        );
    }
}
