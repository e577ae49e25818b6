//! One Arrow table as one Parquet file, and back.
//!
//! Writing is deterministic: the same rows give the same bytes whichever
//! way they were assembled (built row by row in a single run, or read back
//! from shards' files and interleaved by a merge). The writer's input is
//! cut into slices of [`SLICE_ROWS`] rows, so its internal chunking does not
//! depend on how the caller's batch was built; row groups hold
//! [`ROW_GROUP_ROWS`] rows; compression is zstd at [`ZSTD_LEVEL`]; no time
//! or host is written (the footer's `created_by` names the parquet crate
//! version, which pinsight pins).
//!
//! The columns of a row group are encoded in parallel (rayon; the parquet
//! crate's `ArrowColumnWriter`), each column given the same slices in the
//! same order as `ArrowWriter` would give it: the bytes are `ArrowWriter`'s
//! (tested), the time of a merge's tables about halved on two cores.

use arrow_array::RecordBatch;
use arrow_schema::{DataType, SchemaRef};
use parquet::arrow::ArrowWriter;
use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
use parquet::arrow::arrow_writer::compute_leaves;
use parquet::basic::{Compression, Encoding, ZstdLevel};
use parquet::file::properties::{EnabledStatistics, WriterProperties};
use parquet::schema::types::ColumnPath;
use rayon::prelude::*;
use std::path::Path;

/// Rows handed to the writer at a time.
pub const SLICE_ROWS: usize = 65_536;
/// Rows per row group (readers parallelise and skip by row group).
pub const ROW_GROUP_ROWS: usize = 1 << 20;
/// zstd level: 3 is zstd's own default; higher levels cost write time for
/// a few per cent (BENCHMARKS.md, "Plant scale").
pub const ZSTD_LEVEL: i32 = 3;

/// Why a table could not be written or read.
#[derive(Debug, thiserror::Error)]
pub enum ParquetError {
    #[error("{0}")]
    Parquet(#[from] parquet::errors::ParquetError),
    #[error("{0}")]
    Arrow(#[from] arrow_schema::ArrowError),
    #[error("{path}: {message}")]
    File { path: String, message: String },
}

/// The writer's settings for a table of `schema`. Floating-point columns
/// are written BYTE_STREAM_SPLIT without a dictionary: measurements are
/// almost never repeated, so the dictionary only overflows (it made them
/// larger than their raw 4 bytes), while splitting the bytes of each value
/// into streams gives zstd the exponent and high mantissa bytes, which
/// barely change, in runs. On 2 000 synthetic images the `pins` table
/// shrank from 1.30 MB to 0.76 MB (BENCHMARKS.md, "Plant scale").
fn properties(schema: &SchemaRef, group_rows: usize) -> Result<WriterProperties, ParquetError> {
    let mut b = WriterProperties::builder()
        .set_compression(Compression::ZSTD(ZstdLevel::try_new(ZSTD_LEVEL)?))
        .set_max_row_group_row_count(Some(group_rows))
        .set_statistics_enabled(EnabledStatistics::Page);
    for f in schema.fields() {
        if matches!(f.data_type(), DataType::Float32 | DataType::Float64) {
            let col = ColumnPath::from(f.name().as_str());
            b = b
                .set_column_dictionary_enabled(col.clone(), false)
                .set_column_encoding(col, Encoding::BYTE_STREAM_SPLIT);
        }
    }
    Ok(b.build())
}

/// The table as the bytes of one Parquet file.
pub fn write_table(batch: &RecordBatch) -> Result<Vec<u8>, ParquetError> {
    write_in_groups(batch, ROW_GROUP_ROWS)
}

/// [`write_table`] with row groups of `group_rows` (a multiple of
/// [`SLICE_ROWS`], so each row group starts a slice as in `ArrowWriter`).
fn write_in_groups(batch: &RecordBatch, group_rows: usize) -> Result<Vec<u8>, ParquetError> {
    let schema = batch.schema();
    let props = properties(&schema, group_rows)?;
    let mut out = Vec::new();
    let writer = ArrowWriter::try_new(&mut out, schema.clone(), Some(props))?;
    let (mut file, factory) = writer.into_serialized_writer()?;
    let (mut start, mut group) = (0, 0);
    while start < batch.num_rows() {
        let rows = group_rows.min(batch.num_rows() - start);
        let part = batch.slice(start, rows);
        let writers = factory.create_column_writers(group)?;
        if writers.len() != schema.fields().len() {
            return Err(ParquetError::File {
                path: String::new(),
                message: "nested columns are not written by this writer".into(),
            });
        }
        let chunks = writers
            .into_par_iter()
            .zip(schema.fields().par_iter())
            .enumerate()
            .map(|(i, (mut w, field))| {
                let mut at = 0;
                while at < rows {
                    let n = SLICE_ROWS.min(rows - at);
                    for leaf in compute_leaves(field, &part.column(i).slice(at, n))? {
                        w.write(&leaf)?;
                    }
                    at += n;
                }
                w.close()
            })
            .collect::<Result<Vec<_>, _>>()?;
        let mut rg = file.next_row_group()?;
        for c in chunks {
            c.append_to_row_group(&mut rg)?;
        }
        rg.close()?;
        start += rows;
        group += 1;
    }
    file.close()?;
    Ok(out)
}

/// Reads a Parquet file into one table of `schema` (the file's columns in
/// `schema`'s order; a column `schema` names that the file lacks is an
/// error naming the file).
pub fn read_file(path: &Path, schema: &SchemaRef) -> Result<RecordBatch, ParquetError> {
    let name = path.display().to_string();
    let file_err = |message: String| ParquetError::File {
        path: name.clone(),
        message,
    };
    let f = std::fs::File::open(path).map_err(|e| file_err(e.to_string()))?;
    let reader = ParquetRecordBatchReaderBuilder::try_new(f)
        .map_err(|e| file_err(format!("not a Parquet file: {e}")))?
        .with_batch_size(SLICE_ROWS)
        .build()
        .map_err(|e| file_err(e.to_string()))?;
    let mut batches = Vec::new();
    for b in reader {
        let b = b.map_err(|e| file_err(e.to_string()))?;
        batches.push(conform(&b, schema).map_err(file_err)?);
    }
    arrow_select::concat::concat_batches(schema, &batches).map_err(|e| file_err(e.to_string()))
}

/// `b`'s columns picked and ordered as `schema` names them, each of the
/// type `schema` gives.
pub fn conform(b: &RecordBatch, schema: &SchemaRef) -> Result<RecordBatch, String> {
    let mut cols = Vec::with_capacity(schema.fields().len());
    for f in schema.fields() {
        let c = b
            .column_by_name(f.name())
            .ok_or_else(|| format!("no column `{}`", f.name()))?;
        if c.data_type() != f.data_type() {
            return Err(format!(
                "column `{}` is {}, expected {}",
                f.name(),
                c.data_type(),
                f.data_type()
            ));
        }
        cols.push(c.clone());
    }
    RecordBatch::try_new(schema.clone(), cols).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use arrow_array::{ArrayRef, Float64Array, StringArray, UInt64Array};
    use arrow_schema::{DataType, Field, Schema};
    use std::sync::Arc;

    fn table(n: usize) -> RecordBatch {
        let schema = Arc::new(Schema::new(vec![
            Field::new("item", DataType::UInt64, false),
            Field::new("name", DataType::Utf8, true),
            Field::new("x", DataType::Float64, true),
        ]));
        let item: ArrayRef = Arc::new(UInt64Array::from_iter_values(0..n as u64));
        let name: ArrayRef = Arc::new(StringArray::from_iter(
            (0..n).map(|i| (i % 7 != 0).then(|| format!("img-{}", i % 13))),
        ));
        let x: ArrayRef = Arc::new(Float64Array::from_iter(
            (0..n).map(|i| (i % 5 != 0).then_some(i as f64 * 0.1)),
        ));
        RecordBatch::try_new(schema, vec![item, name, x]).unwrap()
    }

    #[test]
    fn same_rows_same_bytes_however_assembled() {
        let t = table(150_000);
        let a = write_table(&t).unwrap();
        // Assembled from pieces of other sizes (as a merge does).
        let pieces = [t.slice(0, 1), t.slice(1, 99_999), t.slice(100_000, 50_000)];
        let joined = arrow_select::concat::concat_batches(&t.schema(), &pieces).unwrap();
        assert_eq!(write_table(&joined).unwrap(), a);
        // And read back: the same table, the same bytes again.
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("t.parquet");
        std::fs::write(&p, &a).unwrap();
        let back = read_file(&p, &t.schema()).unwrap();
        assert_eq!(back, t);
        assert_eq!(write_table(&back).unwrap(), a);
    }

    /// The writer `write_table` replaced: `ArrowWriter` fed the same slices.
    fn sequential(batch: &RecordBatch, group_rows: usize) -> Vec<u8> {
        let mut out = Vec::new();
        let props = properties(&batch.schema(), group_rows).unwrap();
        let mut w = ArrowWriter::try_new(&mut out, batch.schema(), Some(props)).unwrap();
        let mut at = 0;
        while at < batch.num_rows() {
            let n = SLICE_ROWS.min(batch.num_rows() - at);
            w.write(&batch.slice(at, n)).unwrap();
            at += n;
        }
        w.close().unwrap();
        out
    }

    #[test]
    fn columns_encoded_in_parallel_give_arrow_writers_bytes() {
        let t = table(300_000);
        // Three row groups of two slices (and a short last one).
        let groups = 2 * SLICE_ROWS;
        assert_eq!(write_in_groups(&t, groups).unwrap(), sequential(&t, groups));
        assert_eq!(write_table(&t).unwrap(), sequential(&t, ROW_GROUP_ROWS));
        let empty = t.slice(0, 0);
        assert_eq!(
            write_table(&empty).unwrap(),
            sequential(&empty, ROW_GROUP_ROWS)
        );
    }

    #[test]
    fn a_broken_or_foreign_file_is_an_error_naming_it() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("bad.parquet");
        std::fs::write(&p, b"PAR1 this is not parquet PAR1").unwrap();
        let t = table(10);
        let e = read_file(&p, &t.schema()).unwrap_err().to_string();
        assert!(e.contains("bad.parquet"), "{e}");
        // Truncated: the first half of a real file.
        let bytes = write_table(&t).unwrap();
        std::fs::write(&p, &bytes[..bytes.len() / 2]).unwrap();
        let e = read_file(&p, &t.schema()).unwrap_err().to_string();
        assert!(e.contains("bad.parquet"), "{e}");
        // Another table's file: a column is missing.
        let other = Arc::new(Schema::new(vec![Field::new("y", DataType::Utf8, true)]));
        std::fs::write(&p, &bytes).unwrap();
        let e = read_file(&p, &other).unwrap_err().to_string();
        assert!(e.contains("no column `y`"), "{e}");
    }
}
