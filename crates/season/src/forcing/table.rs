//! The CSV layer shared by the forcing formats: comment lines and their `key = value`
//! metadata, the header, typed and range-checked cells that name their line and column, and
//! the even-step check of the times.

use super::{
    ForcingError, ForcingTime, MAX_COLUMNS, MAX_FIELD_BYTES, MAX_LINE_BYTES, MAX_RECORDS,
    STATION_ALTITUDE_RANGE_M, in_range,
};
use crate::clip_for_message;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// A column the reader found in the header.
#[derive(Debug, Clone, Copy)]
pub(super) struct Column {
    /// 0-based index in the record.
    pub index: usize,
    /// The name the format knows it by.
    pub name: &'static str,
}

/// The time of one record, where it came from.
#[derive(Debug, Clone)]
pub(super) struct Stamp {
    pub line: u64,
    pub time: ForcingTime,
    pub text: String,
    /// Whether the text was a bare date (a daily series).
    pub date_only: bool,
}

/// A parsed CSV file: header, records with their line numbers, comment metadata.
pub(super) struct Table {
    path: PathBuf,
    header_line: u64,
    /// Trimmed, lower-cased column names.
    names: Vec<String>,
    /// Each non-empty name's 0-based index (a name appears once).
    index: HashMap<String, usize>,
    /// Data records with the 1-based line each starts on.
    pub rows: Vec<(u64, csv::StringRecord)>,
    /// From a `# station_altitude_m = ...` comment.
    pub station_altitude_m: Option<f64>,
}

fn is_comment(line: &str) -> bool {
    line.trim_start().starts_with('#')
}

impl Table {
    /// Splits off comments (keeping line numbers) and reads the CSV.
    pub fn parse(text: &str, path: &Path) -> Result<Self, ForcingError> {
        let mut station_altitude_m = None;
        let mut csv_text = String::with_capacity(text.len());
        // The header and the records; bounded before the CSV reader allocates any of them.
        let mut data_lines = 0usize;
        for (k, line) in text.lines().enumerate() {
            let number = k as u64 + 1;
            if line.len() > MAX_LINE_BYTES {
                return Err(ForcingError::LineTooLong {
                    path: path.to_path_buf(),
                    line: number,
                    bytes: line.len(),
                    max: MAX_LINE_BYTES,
                });
            }
            if is_comment(line) {
                let body = line.trim_start().trim_start_matches('#');
                if let Some((key, value)) = body.split_once(['=', ':'])
                    && key.trim().eq_ignore_ascii_case("station_altitude_m")
                {
                    let v = value.trim();
                    match v.parse::<f64>() {
                        Ok(a) if in_range(a, STATION_ALTITUDE_RANGE_M) => {
                            station_altitude_m = Some(a)
                        }
                        _ => {
                            return Err(ForcingError::BadAltitude {
                                path: path.to_path_buf(),
                                line: number,
                                value: clip_for_message(v),
                            });
                        }
                    }
                }
            } else if !line.trim().is_empty() {
                data_lines += 1;
                if data_lines > MAX_RECORDS + 1 {
                    return Err(ForcingError::TooManyRecords {
                        path: path.to_path_buf(),
                        line: number,
                        max: MAX_RECORDS,
                    });
                }
                csv_text.push_str(line);
            }
            // Comment and blank lines stay as empty lines, which the CSV reader skips.
            csv_text.push('\n');
        }
        // The CSV reader's own line count skips blank lines, and the byte offset of a record
        // is where the blank lines before it start: skip them, then map the offset to a line.
        let line_starts: Vec<usize> = std::iter::once(0)
            .chain(csv_text.match_indices('\n').map(|(at, _)| at + 1))
            .collect();
        let line_of = |p: Option<&csv::Position>| -> u64 {
            let Some(p) = p else { return 0 };
            let mut at = p.byte() as usize;
            while csv_text.as_bytes().get(at) == Some(&b'\n') {
                at += 1;
            }
            line_starts.partition_point(|&s| s <= at) as u64
        };
        let mut reader = csv::ReaderBuilder::new()
            .has_headers(false)
            .flexible(false)
            .trim(csv::Trim::All)
            .from_reader(csv_text.as_bytes());
        let csv_error = |e: csv::Error| ForcingError::Csv {
            path: path.to_path_buf(),
            line: line_of(e.position()),
            message: match e.kind() {
                csv::ErrorKind::UnequalLengths {
                    expected_len, len, ..
                } => format!("{len} fields where the header has {expected_len}"),
                _ => clip_for_message(&e.to_string()),
            },
        };
        // Every field within MAX_FIELD_BYTES (a line is within MAX_LINE_BYTES already).
        let check_fields = |r: &csv::StringRecord, line: u64| -> Result<(), ForcingError> {
            match r.iter().position(|f| f.len() > MAX_FIELD_BYTES) {
                None => Ok(()),
                Some(k) => Err(ForcingError::FieldTooLong {
                    path: path.to_path_buf(),
                    line,
                    column_number: k + 1,
                    bytes: r.get(k).map_or(0, str::len),
                    max: MAX_FIELD_BYTES,
                }),
            }
        };
        let mut records = reader.records();
        let header = match records.next() {
            Some(r) => r.map_err(csv_error)?,
            None => {
                return Err(ForcingError::NoHeader {
                    path: path.to_path_buf(),
                    expected: super::generic::HEADER,
                });
            }
        };
        let header_line = line_of(header.position());
        if header.len() > MAX_COLUMNS {
            return Err(ForcingError::TooManyColumns {
                path: path.to_path_buf(),
                line: header_line,
                columns: header.len(),
                max: MAX_COLUMNS,
            });
        }
        check_fields(&header, header_line)?;
        let names: Vec<String> = header.iter().map(|h| h.trim().to_lowercase()).collect();
        // One pass with a map: linear in the header's length (a search of the earlier names
        // for each column was quadratic: 13.7 s for 10^5 columns).
        let mut index = HashMap::with_capacity(names.len());
        for (second, name) in names.iter().enumerate() {
            if name.is_empty() {
                continue;
            }
            if let Some(&first) = index.get(name.as_str()) {
                return Err(ForcingError::DuplicateColumn {
                    path: path.to_path_buf(),
                    line: header_line,
                    column: clip_for_message(name),
                    first: first + 1,
                    second: second + 1,
                });
            }
            index.insert(name.clone(), second);
        }
        let mut rows = Vec::with_capacity(data_lines.saturating_sub(1));
        for r in records {
            let r = r.map_err(csv_error)?;
            let line = line_of(r.position());
            check_fields(&r, line)?;
            rows.push((line, r));
        }
        if rows.is_empty() {
            return Err(ForcingError::NoRecords {
                path: path.to_path_buf(),
            });
        }
        Ok(Self {
            path: path.to_path_buf(),
            header_line,
            names,
            index,
            rows,
            station_altitude_m,
        })
    }

    /// Whether the header names `name` (case-insensitive).
    pub fn has(&self, name: &str) -> bool {
        self.index.contains_key(name)
    }

    /// Whether the header is snobal's (`air_temp` and `precip_mass`).
    pub fn is_snobal(&self) -> bool {
        self.has("air_temp") && self.has("precip_mass")
    }

    /// The column named `name`, if the header has it.
    pub fn column(&self, name: &'static str) -> Option<Column> {
        self.index.get(name).map(|&index| Column { index, name })
    }

    /// The column named `name`, which `format` needs.
    pub fn require(
        &self,
        name: &'static str,
        format: &'static str,
    ) -> Result<Column, ForcingError> {
        self.column(name)
            .ok_or_else(|| ForcingError::MissingColumn {
                path: self.path.clone(),
                line: self.header_line,
                column: name,
                format,
                header: clip_for_message(&self.names.join(",")),
            })
    }

    fn bad(&self, line: u64, col: Column, value: &str, expected: String) -> ForcingError {
        ForcingError::BadValue {
            path: self.path.clone(),
            line,
            column_number: col.index + 1,
            column: col.name.to_string(),
            value: clip_for_message(value),
            expected,
        }
    }

    /// A finite number within `range` in an optional column: `None` without the column or
    /// for an empty cell.
    pub fn optional(
        &self,
        row: &(u64, csv::StringRecord),
        col: Option<Column>,
        range: (f64, f64),
        unit: &str,
    ) -> Result<Option<f64>, ForcingError> {
        let Some(col) = col else { return Ok(None) };
        let text = row.1.get(col.index).unwrap_or("");
        if text.is_empty() {
            return Ok(None);
        }
        self.number_in(row.0, col, text, range, unit).map(Some)
    }

    /// A finite number within `range` in a required column.
    pub fn required(
        &self,
        row: &(u64, csv::StringRecord),
        col: Column,
        range: (f64, f64),
        unit: &str,
    ) -> Result<f64, ForcingError> {
        let text = row.1.get(col.index).unwrap_or("");
        self.number_in(row.0, col, text, range, unit)
    }

    fn number_in(
        &self,
        line: u64,
        col: Column,
        text: &str,
        (lo, hi): (f64, f64),
        unit: &str,
    ) -> Result<f64, ForcingError> {
        let expected = || format!("a number of {unit} within {lo}..={hi}");
        match text.parse::<f64>() {
            Ok(v) if in_range(v, (lo, hi)) => Ok(v),
            _ => Err(self.bad(line, col, text, expected())),
        }
    }

    /// A value that passed its own range check but fails a check against another
    /// (precipitation per step, vapour pressure against saturation).
    pub fn reject(
        &self,
        row: &(u64, csv::StringRecord),
        col: Column,
        expected: String,
    ) -> ForcingError {
        self.bad(row.0, col, row.1.get(col.index).unwrap_or(""), expected)
    }

    /// The time in `col` of a record.
    pub fn time(&self, row: &(u64, csv::StringRecord), col: Column) -> Result<Stamp, ForcingError> {
        let text = row.1.get(col.index).unwrap_or("");
        let time = ForcingTime::parse(text)
            .map_err(|why| self.bad(row.0, col, text, format!("a time: {why}")))?;
        Ok(Stamp {
            line: row.0,
            time,
            text: clip_for_message(text),
            date_only: !text.contains(['T', ' ', ':']),
        })
    }

    /// The start and step of evenly spaced, increasing times.
    pub fn check_times(&self, times: &[Stamp]) -> Result<(ForcingTime, f64), ForcingError> {
        let first = &times[0];
        let t0 = first.time.minutes_since_epoch();
        let step_minutes = match times.get(1) {
            None => {
                return Ok((first.time, if first.date_only { 24.0 } else { 1.0 }));
            }
            Some(s) => s.time.minutes_since_epoch() - t0,
        };
        for pair in times.windows(2) {
            let (prev, this) = (&pair[0], &pair[1]);
            let (a, b) = (
                prev.time.minutes_since_epoch(),
                this.time.minutes_since_epoch(),
            );
            if b <= a {
                return Err(ForcingError::NonMonotonicTime {
                    path: self.path.clone(),
                    line: this.line,
                    value: this.text.clone(),
                    previous: prev.text.clone(),
                });
            }
            if b - a != step_minutes {
                return Err(ForcingError::UnevenStep {
                    path: self.path.clone(),
                    line: this.line,
                    value: this.text.clone(),
                    expected: ForcingTime::from_minutes_since_epoch(a + step_minutes).to_string(),
                    step_hours: step_minutes as f64 / 60.0,
                });
            }
        }
        Ok((first.time, step_minutes as f64 / 60.0))
    }
}
