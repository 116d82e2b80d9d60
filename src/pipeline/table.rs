//! Tables as stages produce them, and their Parquet encoding.
//!
//! Every column carries its unit and a one-line description as Arrow field
//! metadata (`unit`, `description`); every file carries the stage's parameters
//! and provenance as Parquet key-value metadata. Encoding is deterministic: the
//! same table gives the same bytes.

use std::collections::{BTreeMap, HashMap};
use std::path::Path;
use std::sync::Arc;

use arrow_array::{ArrayRef, Float64Array, RecordBatch, StringArray, UInt32Array};
use arrow_schema::{Field, Schema};
use parquet::arrow::ArrowWriter;
use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
use parquet::basic::{Compression, ZstdLevel};
use parquet::file::metadata::KeyValue;
use parquet::file::properties::WriterProperties;
use sha2::{Digest, Sha256};

/// Rows per Parquet row group: large enough for compression, small enough to
/// stream.
const ROW_GROUP_ROWS: usize = 1 << 20;

/// One column with its physical meaning.
pub struct Column {
    field: Field,
    values: ArrayRef,
}

impl Column {
    fn new(
        name: &str,
        unit: &str,
        description: &str,
        null: Option<&str>,
        values: ArrayRef,
    ) -> Column {
        let mut metadata = HashMap::from([
            ("unit".to_string(), unit.to_string()),
            ("description".to_string(), description.to_string()),
        ]);
        // Nullable exactly where declared, whether or not this table has a
        // null, so that every table of a stage (and every shard) has one schema.
        if let Some(meaning) = null {
            metadata.insert("null".to_string(), meaning.to_string());
        }
        let field =
            Field::new(name, values.data_type().clone(), null.is_some()).with_metadata(metadata);
        Column { field, values }
    }

    /// A `float64` column; `unit` is e.g. `v_th`, `l/v_th` or `1` (dimensionless).
    /// A NaN (a value that is missing or undefined) is written as a Parquet
    /// null: any reader sees it as missing, and no NaN's sign or payload
    /// (which the compiler and CPU decide) reaches the bytes. A column may
    /// hold nulls only when `null` says what one means (the field is then
    /// nullable and carries the meaning as its `null` metadata);
    /// [`Table::new`] refuses a null elsewhere, and an infinite value
    /// anywhere. [`f64_values`] reads nulls back as NaN.
    pub fn f64(
        name: &str,
        unit: &str,
        description: &str,
        null: Option<&str>,
        values: Vec<f64>,
    ) -> Column {
        let values = values
            .into_iter()
            .map(|value| (!value.is_nan()).then_some(value))
            .collect();
        Column::optional_f64(name, unit, description, null, values)
    }

    /// A `float64` column with `None` for each null (see [`Column::f64`]).
    pub fn optional_f64(
        name: &str,
        unit: &str,
        description: &str,
        null: Option<&str>,
        values: Vec<Option<f64>>,
    ) -> Column {
        let values = Float64Array::from(values);
        Column::new(name, unit, description, null, Arc::new(values))
    }

    /// A `uint32` column (counts).
    pub fn u32(name: &str, unit: &str, description: &str, values: Vec<u32>) -> Column {
        Column::new(
            name,
            unit,
            description,
            None,
            Arc::new(UInt32Array::from(values)),
        )
    }

    /// A `utf8` column (labels).
    pub fn text(name: &str, description: &str, values: Vec<String>) -> Column {
        Column::new(
            name,
            "",
            description,
            None,
            Arc::new(StringArray::from(values)),
        )
    }
}

/// A named table with file-level metadata, as a stage returns it.
pub struct Table {
    /// File stem: the table is written as `<name>.parquet`.
    pub name: String,
    /// The data.
    pub batch: RecordBatch,
    /// Key-value metadata added by the stage (the executor adds provenance).
    pub metadata: BTreeMap<String, String>,
}

/// A table could not be assembled or encoded.
#[derive(Debug, thiserror::Error)]
pub enum TableError {
    /// Columns of different lengths or an Arrow failure.
    #[error("table `{name}`")]
    Arrow {
        /// The table.
        name: String,
        /// The cause.
        source: arrow_schema::ArrowError,
    },
    /// Parquet encoding or decoding failed.
    #[error("parquet: {0}")]
    Parquet(#[from] parquet::errors::ParquetError),
    /// The file could not be read.
    #[error("{path}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
}

impl Table {
    /// Assembles a table from equally long columns; refuses a null in a
    /// column not declared nullable and an infinite value in any (a missing
    /// bound is a null that says so).
    pub fn new(name: &str, columns: Vec<Column>) -> Result<Table, TableError> {
        let infinite = columns.iter().find(|c| {
            c.values
                .as_any()
                .downcast_ref::<Float64Array>()
                .is_some_and(|values| values.iter().flatten().any(f64::is_infinite))
        });
        if let Some(column) = infinite {
            return Err(TableError::Arrow {
                name: name.to_string(),
                source: arrow_schema::ArrowError::InvalidArgumentError(format!(
                    "column `{}` holds an infinite value",
                    column.field.name()
                )),
            });
        }
        let (fields, arrays): (Vec<Field>, Vec<ArrayRef>) =
            columns.into_iter().map(|c| (c.field, c.values)).unzip();
        let batch =
            RecordBatch::try_new(Arc::new(Schema::new(fields)), arrays).map_err(|source| {
                TableError::Arrow {
                    name: name.to_string(),
                    source,
                }
            })?;
        Ok(Table {
            name: name.to_string(),
            batch,
            metadata: BTreeMap::new(),
        })
    }

    /// Adds a key-value metadata entry; keys start with `ternary.` (see
    /// [`content_sha256_of_file`]).
    pub fn with_metadata(mut self, key: &str, value: String) -> Table {
        debug_assert!(key.starts_with("ternary."), "metadata key `{key}`");
        self.metadata.insert(key.to_string(), value);
        self
    }

    /// SHA-256 over a canonical encoding of the data: table name, metadata,
    /// and per column its name, type, field metadata and values (little-endian
    /// bits; strings length-prefixed). Independent of the Parquet encoding and of
    /// the provenance the executor adds, so a recomputation that reproduces the
    /// data leaves downstream keys unchanged.
    pub fn content_sha256(&self) -> Result<String, TableError> {
        let mut hasher = Sha256::new();
        let mut feed = |bytes: &[u8]| {
            hasher.update((bytes.len() as u64).to_le_bytes());
            hasher.update(bytes);
        };
        feed(self.name.as_bytes());
        for (key, value) in &self.metadata {
            feed(key.as_bytes());
            feed(value.as_bytes());
        }
        let schema = self.batch.schema();
        for (field, column) in schema.fields().iter().zip(self.batch.columns()) {
            feed(field.name().as_bytes());
            feed(field.data_type().to_string().as_bytes());
            let metadata: BTreeMap<&String, &String> = field.metadata().iter().collect();
            for (key, value) in metadata {
                feed(key.as_bytes());
                feed(value.as_bytes());
            }
            let any = column.as_any();
            if let Some(values) = any.downcast_ref::<Float64Array>() {
                values
                    .iter()
                    .for_each(|v| feed(&v.map_or(u64::MAX, f64::to_bits).to_le_bytes()));
            } else if let Some(values) = any.downcast_ref::<UInt32Array>() {
                values
                    .iter()
                    .for_each(|v| feed(&v.map_or(u64::MAX, u64::from).to_le_bytes()));
            } else if let Some(values) = any.downcast_ref::<StringArray>() {
                values
                    .iter()
                    .for_each(|v| feed(v.unwrap_or("\u{0}null").as_bytes()));
            } else {
                return Err(TableError::Arrow {
                    name: self.name.clone(),
                    source: arrow_schema::ArrowError::NotYetImplemented(format!(
                        "content hash of column `{}` of type {}",
                        field.name(),
                        field.data_type()
                    )),
                });
            }
        }
        Ok(hasher
            .finalize()
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect())
    }

    /// Number of rows.
    pub fn rows(&self) -> u64 {
        self.batch.num_rows() as u64
    }

    /// Parquet bytes (zstd, deterministic). This table's metadata plus `extra`
    /// are stored twice: as Parquet key-value metadata (for any Parquet reader,
    /// e.g. DuckDB's `parquet_kv_metadata`) and as the Arrow schema's metadata
    /// (which pyarrow and polars attach to the schema they read).
    pub fn to_parquet(&self, extra: &BTreeMap<String, String>) -> Result<Vec<u8>, TableError> {
        let entries: BTreeMap<String, String> = self
            .metadata
            .iter()
            .chain(extra)
            .map(|(k, v)| (k.clone(), v.clone()))
            .collect();
        let metadata: HashMap<String, String> = entries.clone().into_iter().collect();
        let key_values = entries
            .into_iter()
            .map(|(k, v)| KeyValue::new(k, v))
            .collect();
        let schema = Arc::new(self.batch.schema().as_ref().clone().with_metadata(metadata));
        let batch = RecordBatch::try_new(schema.clone(), self.batch.columns().to_vec()).map_err(
            |source| TableError::Arrow {
                name: self.name.clone(),
                source,
            },
        )?;
        let properties = WriterProperties::builder()
            .set_compression(Compression::ZSTD(ZstdLevel::try_new(3)?))
            .set_max_row_group_row_count(Some(ROW_GROUP_ROWS))
            .set_key_value_metadata(Some(key_values))
            .build();
        let mut bytes = Vec::new();
        let mut writer = ArrowWriter::try_new(&mut bytes, schema, Some(properties))?;
        writer.write(&batch)?;
        writer.close()?;
        Ok(bytes)
    }
}

/// A named column of a batch as a concrete Arrow array type.
pub fn column<'a, T: 'static>(batch: &'a RecordBatch, name: &str) -> Result<&'a T, TableError> {
    let missing = || TableError::Arrow {
        name: name.to_string(),
        source: arrow_schema::ArrowError::SchemaError(format!(
            "column `{name}` is missing or has an unexpected type"
        )),
    };
    batch
        .column_by_name(name)
        .and_then(|c| c.as_any().downcast_ref::<T>())
        .ok_or_else(missing)
}

/// A `float64` column as a vector (nulls become NaN).
pub fn f64_values(batch: &RecordBatch, name: &str) -> Result<Vec<f64>, TableError> {
    Ok(column::<Float64Array>(batch, name)?
        .iter()
        .map(|v| v.unwrap_or(f64::NAN))
        .collect())
}

/// A `uint32` column as a vector (nulls become 0).
pub fn u32_values(batch: &RecordBatch, name: &str) -> Result<Vec<u32>, TableError> {
    Ok(column::<UInt32Array>(batch, name)?
        .iter()
        .map(|v| v.unwrap_or(0))
        .collect())
}

/// A `utf8` column as a vector (nulls become empty).
pub fn text_values(batch: &RecordBatch, name: &str) -> Result<Vec<String>, TableError> {
    Ok(column::<StringArray>(batch, name)?
        .iter()
        .map(|v| v.unwrap_or_default().to_string())
        .collect())
}

/// Key-value metadata the executor stamps into every file: provenance, not
/// content (left out of [`Table::content_sha256`]).
pub const PROVENANCE_KEYS: [&str; 6] = [
    "ternary.stage",
    "ternary.code",
    "ternary.key",
    "ternary.params",
    "ternary.inputs",
    "ternary.tool",
];

/// Reads a whole Parquet file into one batch, with its key-value metadata.
pub fn read_parquet(path: &Path) -> Result<(RecordBatch, BTreeMap<String, String>), TableError> {
    let bytes = std::fs::read(path).map_err(|source| TableError::Io {
        path: path.display().to_string(),
        source,
    })?;
    read_parquet_bytes(&path.display().to_string(), bytes)
}

/// A Parquet file's key-value metadata.
fn key_values(metadata: &parquet::file::metadata::FileMetaData) -> BTreeMap<String, String> {
    metadata
        .key_value_metadata()
        .map(|entries| {
            entries
                .iter()
                .map(|kv| (kv.key.clone(), kv.value.clone().unwrap_or_default()))
                .collect()
        })
        .unwrap_or_default()
}

/// The schema (with field metadata), key-value metadata and row count of a
/// Parquet file, read from its footer without decoding the data.
pub fn read_parquet_footer(
    path: &Path,
) -> Result<(arrow_schema::SchemaRef, BTreeMap<String, String>, u64), TableError> {
    let file = std::fs::File::open(path).map_err(|source| TableError::Io {
        path: path.display().to_string(),
        source,
    })?;
    let builder = ParquetRecordBatchReaderBuilder::try_new(file)?;
    let metadata = builder.metadata().file_metadata();
    let rows = u64::try_from(metadata.num_rows()).unwrap_or(0);
    Ok((builder.schema().clone(), key_values(metadata), rows))
}

/// Decodes Parquet bytes (already read, and hashed, by the caller) into one
/// batch with its key-value metadata; `label` names the source in errors.
pub fn read_parquet_bytes(
    label: &str,
    bytes: Vec<u8>,
) -> Result<(RecordBatch, BTreeMap<String, String>), TableError> {
    let builder = ParquetRecordBatchReaderBuilder::try_new(bytes::Bytes::from(bytes))?;
    let metadata = key_values(builder.metadata().file_metadata());
    let schema = builder.schema().clone();
    let arrow_error = |source| TableError::Arrow {
        name: label.to_string(),
        source,
    };
    let batches = builder
        .build()?
        .collect::<Result<Vec<_>, _>>()
        .map_err(arrow_error)?;
    let batch = arrow_select::concat::concat_batches(&schema, &batches).map_err(arrow_error)?;
    Ok((batch, metadata))
}

impl Table {
    /// The table a stage returned, rebuilt from the Parquet file `name`
    /// (`<table>.parquet`) with these bytes: its data and column metadata, and
    /// the stage's `ternary.*` metadata without the executor's provenance.
    pub fn from_parquet(name: &str, bytes: Vec<u8>) -> Result<Table, TableError> {
        let (batch, metadata) = read_parquet_bytes(name, bytes)?;
        let plain = Arc::new(
            batch
                .schema()
                .as_ref()
                .clone()
                .with_metadata(HashMap::new()),
        );
        let batch = RecordBatch::try_new(plain, batch.columns().to_vec()).map_err(|source| {
            TableError::Arrow {
                name: name.to_string(),
                source,
            }
        })?;
        Ok(Table {
            name: name.trim_end_matches(".parquet").to_string(),
            batch,
            metadata: metadata
                .into_iter()
                .filter(|(key, _)| {
                    key.starts_with("ternary.") && !PROVENANCE_KEYS.contains(&key.as_str())
                })
                .collect(),
        })
    }

    /// The rows of `parts` (tables of one name, schema and metadata) one after
    /// the other: the table of a sharded stage from its shards, in order.
    pub fn concatenate(parts: Vec<Table>) -> Result<Table, TableError> {
        let first = parts.first().ok_or_else(|| TableError::Arrow {
            name: "(no table)".into(),
            source: arrow_schema::ArrowError::InvalidArgumentError("nothing to concatenate".into()),
        })?;
        let (name, metadata, schema) = (
            first.name.clone(),
            first.metadata.clone(),
            first.batch.schema(),
        );
        if let Some(other) = parts.iter().find(|part| part.metadata != metadata) {
            return Err(TableError::Arrow {
                name: name.clone(),
                source: arrow_schema::ArrowError::InvalidArgumentError(format!(
                    "shards disagree on the metadata of `{}`",
                    other.name
                )),
            });
        }
        let batches: Vec<RecordBatch> = parts.into_iter().map(|part| part.batch).collect();
        let batch = arrow_select::concat::concat_batches(&schema, &batches).map_err(|source| {
            TableError::Arrow {
                name: name.clone(),
                source,
            }
        })?;
        Ok(Table {
            name,
            batch,
            metadata,
        })
    }
}

/// The content hash of an output file `name` with these bytes: for a table
/// (`<table>.parquet`) [`Table::content_sha256`], for any other file (a
/// figure) the SHA-256 of its bytes.
pub fn content_sha256_of_file(name: &str, bytes: Vec<u8>) -> Result<String, TableError> {
    if is_table_file(name) {
        Table::from_parquet(name, bytes)?.content_sha256()
    } else {
        Ok(crate::pipeline::key::sha256_hex(&bytes))
    }
}

/// `true` for a table's file name (`<table>.parquet`), `false` for other files.
pub fn is_table_file(name: &str) -> bool {
    name.ends_with(".parquet")
}
