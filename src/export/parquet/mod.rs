//! Results as Apache Parquet for the data tools a plant already runs
//! (DuckDB, Spark, pandas/polars, pyarrow): issue 19.
//!
//! - [`table`]: an Arrow table written as one Parquet file with fixed
//!   writer settings (zstd, fixed row-group and page sizes, no timestamps),
//!   so equal tables give equal bytes: a merge of shards writes the single
//!   run's files byte for byte; and read back (for the merge).
//! - [`hive`]: hive-style partition folders (`part=…/lot=…/`), written and
//!   read back.
//! - [`yield_tables`]: `yield`'s tables, one row per image and one per pin.
//! - [`cycles`]: `monitor`'s table, one row per cycle.
//!
//! The schemas are documented in docs/scale.md ("Parquet outputs"). Each
//! exporter is a pure function from a result to (file name, bytes); the
//! command stages them in its report (`crate::output`).

pub mod cycles;
pub mod hive;
pub mod table;
pub mod yield_tables;

pub use hive::{PartitionKey, parse_partition_keys};
pub use table::{ParquetError, read_file, write_table};

/// The files of one table in an output folder: `NAME.parquet`, or with
/// partition keys `NAME/k=v/…/FILE` per partition (`FILE` is
/// `data.parquet` for a whole run, `shard-K-of-N.parquet` for a shard, so
/// the shards' trees can be copied into one data set). Paths are relative
/// to the output folder, `/`-separated.
pub fn table_files(
    name: &str,
    batch: &arrow_array::RecordBatch,
    keys: &[PartitionKey],
    file: &str,
) -> Result<Vec<(String, Vec<u8>)>, ParquetError> {
    if keys.is_empty() {
        return Ok(vec![(format!("{name}.parquet"), write_table(batch)?)]);
    }
    use rayon::prelude::*;
    hive::partition(batch, keys)?
        .into_par_iter()
        .map(|(dir, part)| Ok((format!("{name}/{dir}/{file}"), write_table(&part)?)))
        .collect()
}

/// The partition file name of a shard (`data.parquet` for a whole run).
pub fn partition_file_name(k: u32, n: u32) -> String {
    if n <= 1 {
        "data.parquet".into()
    } else {
        format!("shard-{k}-of-{n}.parquet")
    }
}

/// Reads the table `name` of an output folder: `DIR/NAME.parquet`, or the
/// hive-partitioned folder `DIR/NAME/` (every `*.parquet` below it, the
/// partition columns restored from the folder names). `None` when neither
/// exists.
pub fn read_table(
    dir: &std::path::Path,
    name: &str,
    schema: &arrow_schema::SchemaRef,
) -> Result<Option<arrow_array::RecordBatch>, ParquetError> {
    let file = dir.join(format!("{name}.parquet"));
    if file.is_file() {
        return table::read_file(&file, schema).map(Some);
    }
    let folder = dir.join(name);
    if folder.is_dir() {
        return hive::read_partitioned(&folder, schema).map(Some);
    }
    Ok(None)
}
