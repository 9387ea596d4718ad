//! The CSV form of the sweep's rows: RFC 4180 fields, one header line, rows appended and
//! flushed one at a time.

use super::TuneError;
use serde::Serialize;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Quotes a CSV field when it holds a comma, a quote or a line break (RFC 4180).
fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_owned()
    }
}

/// Splits one CSV line into fields (RFC 4180 quoting, no line breaks inside fields).
fn split_csv_line(line: &str) -> Result<Vec<String>, String> {
    let mut fields = Vec::new();
    let mut field = String::new();
    let mut chars = line.chars().peekable();
    let mut quoted = false;
    while let Some(c) = chars.next() {
        match (quoted, c) {
            (true, '"') if chars.peek() == Some(&'"') => {
                field.push('"');
                chars.next();
            }
            (true, '"') => quoted = false,
            (false, '"') if field.is_empty() => quoted = true,
            (false, ',') => fields.push(std::mem::take(&mut field)),
            _ => field.push(c),
        }
    }
    if quoted {
        return Err("an unclosed quote".into());
    }
    fields.push(field);
    Ok(fields)
}

/// A row type of the sweep's CSV files: its columns, in the struct's field order and named
/// as its serde fields, and which of them are text (the others are numbers, empty for
/// `None`).
pub trait CsvRow: Serialize + serde::de::DeserializeOwned {
    const COLUMNS: &'static [&'static str];
    const TEXT_COLUMNS: &'static [&'static str];
    /// What a header of another version means, for the error.
    const OTHER_HEADER: &'static str;

    /// The row as one CSV line (no line break).
    fn csv_line(&self) -> String {
        let value = serde_json::to_value(self).unwrap_or_default();
        Self::COLUMNS
            .iter()
            .map(|c| match &value[*c] {
                serde_json::Value::String(s) => csv_field(s),
                serde_json::Value::Null => String::new(),
                v => v.to_string(),
            })
            .collect::<Vec<_>>()
            .join(",")
    }

    /// Parses a line written by [`CsvRow::csv_line`].
    fn from_csv_line(line: &str) -> Result<Self, String> {
        let fields = split_csv_line(line)?;
        if fields.len() != Self::COLUMNS.len() {
            return Err(format!(
                "{} fields, expected {}",
                fields.len(),
                Self::COLUMNS.len()
            ));
        }
        let mut map = serde_json::Map::new();
        for (c, f) in Self::COLUMNS.iter().zip(fields) {
            let v = if Self::TEXT_COLUMNS.contains(c) {
                serde_json::Value::String(f)
            } else if f.is_empty() {
                serde_json::Value::Null
            } else {
                serde_json::from_str(&f).map_err(|_| format!("{c} = `{f}` is not a number"))?
            };
            map.insert((*c).to_owned(), v);
        }
        serde_json::from_value(serde_json::Value::Object(map)).map_err(|e| e.to_string())
    }

    /// The CSV header line.
    fn csv_header() -> String {
        Self::COLUMNS.join(",")
    }
}

/// Reads a CSV of `T` rows written by [`CsvAppender`] (header and rows).
pub fn read_rows<T: CsvRow>(path: &Path) -> Result<Vec<T>, TuneError> {
    let text = std::fs::read_to_string(path).map_err(|source| TuneError::Io {
        path: path.to_owned(),
        source,
    })?;
    let mut lines = text.lines().enumerate();
    let csv_err = |line: usize, reason: String| TuneError::Csv {
        path: path.to_owned(),
        line: line + 1,
        reason,
    };
    match lines.next() {
        Some((_, h)) if h.trim_end() == T::csv_header() => {}
        _ => return Err(csv_err(0, T::OTHER_HEADER.into())),
    }
    lines
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| T::from_csv_line(l.trim_end()).map_err(|e| csv_err(i, e)))
        .collect()
}

/// Appends `T` rows to a CSV file, writing the header first when the file is new; each row
/// is flushed as it is written, so an interrupted sweep keeps every finished row.
pub struct CsvAppender<T> {
    path: PathBuf,
    file: std::fs::File,
    rows: std::marker::PhantomData<fn(&T)>,
}

impl<T: CsvRow> CsvAppender<T> {
    pub fn open(path: &Path) -> Result<Self, TuneError> {
        let io = |source| TuneError::Io {
            path: path.to_owned(),
            source,
        };
        let new = !path.exists();
        let mut file = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(path)
            .map_err(io)?;
        if new {
            writeln!(file, "{}", T::csv_header()).map_err(io)?;
        }
        Ok(Self {
            path: path.to_owned(),
            file,
            rows: std::marker::PhantomData,
        })
    }

    pub fn append(&mut self, row: &T) -> Result<(), TuneError> {
        writeln!(self.file, "{}", row.csv_line())
            .and_then(|()| self.file.sync_data())
            .map_err(|source| TuneError::Io {
                path: self.path.clone(),
                source,
            })
    }
}
