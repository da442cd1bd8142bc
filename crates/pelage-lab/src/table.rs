//! CSV and terminal tables.

use std::path::Path;

use crate::{LabError, write_file_atomically};

/// A CSV table: header and rows of cells (quote cells containing comma,
/// quote or newline per RFC 4180).
///
/// Every row has as many cells as the header; [`Table::push`] enforces it.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Table {
    /// Column names.
    pub header: Vec<String>,
    /// Data rows, each as wide as `header`.
    pub rows: Vec<Vec<String>>,
}

impl Table {
    /// An empty table with the given column names.
    pub fn new(header: &[&str]) -> Table {
        Table {
            header: header.iter().map(|h| (*h).to_string()).collect(),
            rows: Vec::new(),
        }
    }

    /// Append a row; an error if its width differs from the header's.
    pub fn push(&mut self, row: Vec<String>) -> Result<(), LabError> {
        if row.len() != self.header.len() {
            return Err(LabError::Invalid(format!(
                "table row has {} cells but the header has {} columns ({})",
                row.len(),
                self.header.len(),
                self.header.join(", ")
            )));
        }
        self.rows.push(row);
        Ok(())
    }

    /// The table as CSV: one record per line (`\n` line ends, including the
    /// last), cells quoted per RFC 4180 when they contain a comma, a double
    /// quote, a carriage return or a line feed.
    pub fn to_csv(&self) -> String {
        let mut out = String::new();
        for record in std::iter::once(&self.header).chain(&self.rows) {
            for (i, cell) in record.iter().enumerate() {
                if i > 0 {
                    out.push(',');
                }
                push_csv_cell(&mut out, cell);
            }
            out.push('\n');
        }
        out
    }

    /// Parse CSV as written by [`Table::to_csv`] (RFC 4180; `\n` or `\r\n`
    /// line ends). The first record is the header; every record must be as
    /// wide as the header.
    pub fn from_csv(text: &str) -> Result<Table, LabError> {
        let mut records = parse_csv(text)?.into_iter();
        let header = records
            .next()
            .ok_or_else(|| LabError::Invalid("CSV text has no header line".to_string()))?;
        let mut table = Table {
            header,
            rows: Vec::new(),
        };
        for row in records {
            table.push(row)?;
        }
        Ok(table)
    }

    /// Write the table as CSV to `path`, atomically.
    pub fn write_csv(&self, path: &Path) -> Result<(), LabError> {
        write_file_atomically(path, self.to_csv().as_bytes())
    }

    /// Aligned plain-text table for the terminal (numbers right-aligned, text
    /// left-aligned), with a rule under the header.
    ///
    /// A column is numeric when every non-empty cell in it parses as a number
    /// (a trailing `%` or `x` is allowed); its header is right-aligned too.
    /// Line breaks inside cells are shown as spaces.
    pub fn to_text(&self) -> String {
        let cols = self
            .rows
            .iter()
            .map(Vec::len)
            .chain(std::iter::once(self.header.len()))
            .max()
            .unwrap_or(0);
        let clean = |s: &str| s.replace("\r\n", " ").replace(['\n', '\r'], " ");
        let header: Vec<String> = self.header.iter().map(|c| clean(c)).collect();
        let rows: Vec<Vec<String>> = self
            .rows
            .iter()
            .map(|r| r.iter().map(|c| clean(c)).collect())
            .collect();
        let cell = |row: &[String], c: usize| row.get(c).cloned().unwrap_or_default();
        let mut widths = vec![0usize; cols];
        let mut numeric = vec![true; cols];
        let mut any_value = vec![false; cols];
        for (c, width) in widths.iter_mut().enumerate() {
            *width = char_len(&cell(&header, c));
            for row in &rows {
                let v = cell(row, c);
                *width = (*width).max(char_len(&v));
                if !v.trim().is_empty() {
                    any_value[c] = true;
                    numeric[c] &= is_number(&v);
                }
            }
        }
        let right: Vec<bool> = (0..cols).map(|c| numeric[c] && any_value[c]).collect();
        let mut out = String::new();
        let line = |cells: Vec<String>, out: &mut String| {
            let mut text = String::new();
            for (c, v) in cells.iter().enumerate() {
                if c > 0 {
                    text.push_str("  ");
                }
                let pad = widths[c].saturating_sub(char_len(v));
                if right[c] {
                    text.extend(std::iter::repeat_n(' ', pad));
                    text.push_str(v);
                } else {
                    text.push_str(v);
                    text.extend(std::iter::repeat_n(' ', pad));
                }
            }
            out.push_str(text.trim_end());
            out.push('\n');
        };
        line((0..cols).map(|c| cell(&header, c)).collect(), &mut out);
        line(widths.iter().map(|w| "-".repeat(*w)).collect(), &mut out);
        for row in &rows {
            line((0..cols).map(|c| cell(row, c)).collect(), &mut out);
        }
        out
    }
}

/// Number of characters (not bytes) in `s`.
fn char_len(s: &str) -> usize {
    s.chars().count()
}

/// Whether a cell reads as a number for alignment purposes.
fn is_number(s: &str) -> bool {
    let t = s.trim();
    let t = t
        .strip_suffix('%')
        .or_else(|| t.strip_suffix('x'))
        .unwrap_or(t)
        .trim_end();
    !t.is_empty() && t.parse::<f64>().is_ok()
}

/// Append one CSV cell, quoted when needed.
fn push_csv_cell(out: &mut String, cell: &str) {
    if cell.contains([',', '"', '\n', '\r']) {
        out.push('"');
        out.push_str(&cell.replace('"', "\"\""));
        out.push('"');
    } else {
        out.push_str(cell);
    }
}

/// Split RFC 4180 text into records of cells.
fn parse_csv(text: &str) -> Result<Vec<Vec<String>>, LabError> {
    let mut records = Vec::new();
    let mut record = Vec::new();
    let mut cell = String::new();
    let mut chars = text.chars().peekable();
    let mut in_quotes = false;
    let mut line = 1usize;
    let mut pending = false; // a record has started (any cell or separator seen)
    while let Some(ch) = chars.next() {
        if in_quotes {
            match ch {
                '"' if chars.peek() == Some(&'"') => {
                    chars.next();
                    cell.push('"');
                }
                '"' => in_quotes = false,
                _ => {
                    if ch == '\n' {
                        line += 1;
                    }
                    cell.push(ch);
                }
            }
            continue;
        }
        match ch {
            '"' if cell.is_empty() => {
                in_quotes = true;
                pending = true;
            }
            '"' => {
                return Err(LabError::Invalid(format!(
                    "CSV line {line}: stray double quote inside an unquoted cell"
                )));
            }
            ',' => {
                record.push(std::mem::take(&mut cell));
                pending = true;
            }
            '\r' if chars.peek() == Some(&'\n') => {}
            '\n' | '\r' => {
                record.push(std::mem::take(&mut cell));
                records.push(std::mem::take(&mut record));
                pending = false;
                line += 1;
            }
            _ => {
                cell.push(ch);
                pending = true;
            }
        }
    }
    if in_quotes {
        return Err(LabError::Invalid(format!(
            "CSV line {line}: quoted cell is not closed"
        )));
    }
    if pending {
        record.push(cell);
        records.push(record);
    }
    Ok(records)
}
