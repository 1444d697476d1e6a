//! Reading a bench measurement file: a CSV table with a header row, from which a calibration
//! takes the columns it names, as numbers, each with the line it came from
//! (docs/formats.md#thrust-bench-files).
//!
//! The header is matched by name, ignoring case and surrounding spaces; columns may come in any
//! order and others are ignored. Lines starting with `#` are comments; empty lines and rows
//! with every field empty (a spreadsheet's blank rows) are skipped. Every value of a named
//! column must be a finite number. Errors name the line as a text editor counts it (the
//! header is line 1 when nothing comes before it) and never panic.

use std::fs::File;
use std::io::Read;
use std::path::Path;

use anyhow::{Context, Result, anyhow, bail};

/// Largest bench file read, bytes: a sweep is a few hundred lines; a raw log of a long run at
/// a kilohertz is some tens of megabytes and is better reduced first.
pub const MAX_FILE_BYTES: u64 = 16 * 1024 * 1024;

/// One data row: its line in the file and the values of the columns asked for, in the order
/// they were asked for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Row<const N: usize> {
    /// Line of the file where the row starts (1 for the file's first line).
    pub line: usize,
    /// The named columns' values.
    pub values: [f64; N],
}

/// Reads the file at `path` (at most [`MAX_FILE_BYTES`]) and returns the values of `columns`
/// in each data row. Errors start with the file's name.
pub fn read<const N: usize>(path: &Path, columns: [&str; N]) -> Result<Vec<Row<N>>> {
    let cannot = || format!("cannot read bench file {}", path.display());
    let file = File::open(path).with_context(cannot)?;
    let mut bytes = Vec::new();
    file.take(MAX_FILE_BYTES + 1)
        .read_to_end(&mut bytes)
        .with_context(cannot)?;
    if bytes.len() as u64 > MAX_FILE_BYTES {
        bail!(
            "bench file {} is larger than {} MiB; reduce the log to the sweep's readings",
            path.display(),
            MAX_FILE_BYTES / (1024 * 1024)
        );
    }
    parse(&bytes, columns).with_context(|| path.display().to_string())
}

/// The values of `columns` in each data row of the CSV text `bytes`.
pub fn parse<const N: usize>(bytes: &[u8], columns: [&str; N]) -> Result<Vec<Row<N>>> {
    let wanted = columns.map(|c| c.trim().to_ascii_lowercase());
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .trim(csv::Trim::All)
        .comment(Some(COMMENT))
        .from_reader(bytes);
    let mut record = csv::ByteRecord::new();
    let mut header: Option<[usize; N]> = None;
    let mut rows = Vec::new();
    loop {
        let more = reader.read_byte_record(&mut record).map_err(|e| {
            let line = e
                .position()
                .map_or(0, |p| first_line(bytes, p.byte() as usize));
            anyhow!("line {line}: not CSV ({e})")
        })?;
        if !more {
            break;
        }
        if record.iter().all(<[u8]>::is_empty) {
            continue;
        }
        let line = record
            .position()
            .map_or(0, |p| first_line(bytes, p.byte() as usize));
        match header {
            None => header = Some(find_columns(&record, &wanted, line)?),
            Some(at) => {
                let mut values = [0.0; N];
                for ((value, &index), name) in values.iter_mut().zip(&at).zip(&wanted) {
                    *value = number(record.get(index), name, line)?;
                }
                rows.push(Row { line, values });
            }
        }
    }
    if header.is_none() {
        bail!(
            "line 1: the file is empty (no header row); its first row names the columns {}",
            listed(&wanted)
        );
    }
    Ok(rows)
}

/// The comment character: a line starting with it is skipped.
const COMMENT: u8 = b'#';

/// Where each wanted column is in the header `record` (at `line`).
fn find_columns<const N: usize>(
    record: &csv::ByteRecord,
    wanted: &[String; N],
    line: usize,
) -> Result<[usize; N]> {
    let names: Vec<String> = record
        .iter()
        .map(|field| String::from_utf8_lossy(field).to_ascii_lowercase())
        .collect();
    let mut at = [0; N];
    for (slot, name) in at.iter_mut().zip(wanted) {
        let found: Vec<usize> = (0..names.len()).filter(|&i| names[i] == *name).collect();
        match found[..] {
            [index] => *slot = index,
            [] => bail!(
                "line {line}: the header has no `{name}` column (it names {}; the columns needed are {})",
                listed(&names),
                listed(wanted)
            ),
            [first, second, ..] => bail!(
                "line {line}: the header names `{name}` twice (columns {} and {})",
                first + 1,
                second + 1
            ),
        }
    }
    Ok(at)
}

/// The value of column `name` in a row at `line`: a finite number.
fn number(field: Option<&[u8]>, name: &str, line: usize) -> Result<f64> {
    let text = match field {
        Some(f) if !f.is_empty() => String::from_utf8_lossy(f),
        _ => bail!("line {line}: no `{name}` value"),
    };
    let value: f64 = text
        .parse()
        .map_err(|_| anyhow!("line {line}: `{name}` value `{text}` is not a number"))?;
    if !value.is_finite() {
        bail!("line {line}: `{name}` value `{text}` is not a finite number");
    }
    Ok(value)
}

/// Names as `` `a`, `b` and `c` `` for a message.
fn listed(names: &[String]) -> String {
    let quoted: Vec<String> = names.iter().map(|n| format!("`{n}`")).collect();
    match quoted.split_last() {
        None => "nothing".to_string(),
        Some((last, [])) => last.clone(),
        Some((last, rest)) => format!("{} and {last}", rest.join(", ")),
    }
}

/// The line (1-based) on which the record found from byte `start` begins. The CSV reader
/// reports a record's position as where it began looking, before the byte-order mark, empty
/// lines and comment lines it skipped; those are skipped here too.
fn first_line(bytes: &[u8], start: usize) -> usize {
    const BOM: &[u8] = b"\xEF\xBB\xBF";
    let mut at = start.min(bytes.len());
    if at == 0 && bytes.starts_with(BOM) {
        at = BOM.len();
    }
    while at < bytes.len() {
        let rest = &bytes[at..];
        let skipped = if rest[0] == COMMENT {
            rest.iter()
                .position(|&b| b == b'\n')
                .map_or(rest.len(), |n| n + 1)
        } else if rest.starts_with(b"\r\n") {
            2
        } else if rest[0] == b'\n' || rest[0] == b'\r' {
            1
        } else {
            break;
        };
        at += skipped;
    }
    let before = &bytes[..at];
    1 + before.iter().filter(|&&b| b == b'\n').count() + lone_carriage_returns(before)
}

/// Line breaks written as a lone `\r` (old Mac files), which the CSV reader accepts too.
fn lone_carriage_returns(bytes: &[u8]) -> usize {
    bytes
        .iter()
        .enumerate()
        .filter(|&(i, &b)| b == b'\r' && bytes.get(i + 1) != Some(&b'\n'))
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rows(text: &str) -> Vec<Row<2>> {
        parse(text.as_bytes(), ["command", "thrust_n"]).expect("parses")
    }

    fn error(text: &str) -> String {
        format!(
            "{:#}",
            parse(text.as_bytes(), ["command", "thrust_n"]).unwrap_err()
        )
    }

    #[test]
    fn columns_in_any_order_among_others() {
        let got = rows("time_s, Thrust_N ,command\n0.1,2.5,0.4\n0.2,3.0,0.5\n");
        assert_eq!(
            got,
            [
                Row {
                    line: 2,
                    values: [0.4, 2.5]
                },
                Row {
                    line: 3,
                    values: [0.5, 3.0]
                }
            ]
        );
    }

    #[test]
    fn lines_count_comments_blank_rows_and_carriage_returns() {
        let text = "\u{feff}# bench of 1 May\ncommand,thrust_n\r\n\r\n# motor 2\n# prop 10x4.5\n0.2,1\n,\n\n\"0.4\",\"2\"\n";
        let got: Vec<usize> = rows(text).iter().map(|r| r.line).collect();
        assert_eq!(got, [6, 9]);
        assert_eq!(
            error("\u{feff}# bench of 1 May\n\ncmd,thrust_n\n"),
            "line 3: the header has no `command` column (it names `cmd` and `thrust_n`; the columns needed are `command` and `thrust_n`)"
        );
        assert_eq!(
            error("command,thrust_n\n\n# x\n0.2,abc\n"),
            "line 4: `thrust_n` value `abc` is not a number"
        );
    }

    #[test]
    fn old_mac_line_breaks_count_too() {
        assert_eq!(
            error("command,thrust_n\r0.2,1\r0.4,x\r"),
            "line 3: `thrust_n` value `x` is not a number"
        );
    }

    #[test]
    fn any_bytes_give_rows_or_an_error_never_a_panic() {
        use rand::{RngExt, SeedableRng};
        let alphabet = b"0123456789.,-e\"#\r\n commandthrust_\xff";
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for _ in 0..2000 {
            let len = rng.random_range(0..60);
            let mut text = b"command,thrust_n\n".to_vec();
            text.extend((0..len).map(|_| alphabet[rng.random_range(0..alphabet.len())]));
            if let Err(e) = parse(&text, ["command", "thrust_n"]) {
                assert!(format!("{e:#}").starts_with("line "), "{e:#}");
            }
        }
    }

    #[test]
    fn bad_values_name_the_line_and_the_column() {
        let head = "command,thrust_n\n0.2,1\n";
        assert_eq!(
            error(&format!("{head}0.4,NaN\n")),
            "line 3: `thrust_n` value `NaN` is not a finite number"
        );
        assert_eq!(
            error(&format!("{head}0.4,inf\n")),
            "line 3: `thrust_n` value `inf` is not a finite number"
        );
        assert_eq!(
            error(&format!("{head}0.4\n")),
            "line 3: no `thrust_n` value"
        );
        assert_eq!(
            error(&format!("{head}x0.4,2\n")),
            "line 3: `command` value `x0.4` is not a number"
        );
        assert_eq!(
            error(&format!("{head}0.4,\n")),
            "line 3: no `thrust_n` value"
        );
    }

    #[test]
    fn a_missing_column_or_an_empty_file_is_named() {
        assert_eq!(
            error("cmd,thrust_n\n0.2,1\n"),
            "line 1: the header has no `command` column (it names `cmd` and `thrust_n`; the columns needed are `command` and `thrust_n`)"
        );
        assert_eq!(
            error("command,thrust_n,command\n"),
            "line 1: the header names `command` twice (columns 1 and 3)"
        );
        for empty in ["", "\n\n", "# only a comment\n", ",,\n"] {
            assert_eq!(
                error(empty),
                "line 1: the file is empty (no header row); its first row names the columns `command` and `thrust_n`",
                "{empty:?}"
            );
        }
        // A header alone is a file without readings, which the calibration judges.
        assert!(rows("command,thrust_n\n").is_empty());
    }

    #[test]
    fn bytes_that_are_not_text_do_not_panic() {
        let text = b"command,thrust_n,note\n0.2,1,\xff\xfe\n0.4,\xff\n";
        let err = format!("{:#}", parse(text, ["command", "thrust_n"]).unwrap_err());
        assert!(err.starts_with("line 3: `thrust_n` value"), "{err}");
    }
}
