//! Reading ground-motion files: PEER `.AT2` files (units of g), two-column
//! CSV `time,accel` tables (m/s^2) and single-column files, each as a
//! [`GroundMotion`] constructor, with every size bounded (see
//! [`crate::limits`]).
//!
//! An `.AT2` file's first value is at t = 0 and the n-th at n DT.

use super::record::{GroundMotion, RecordError};
use crate::limits::{
    quote, record_step_allowed, Num, MAX_RECORD_ACCEL, MAX_RECORD_BYTES, MAX_RECORD_LINE,
    MAX_RECORD_SAMPLES, MAX_RECORD_TIME, MIN_RECORD_DT,
};
use std::collections::hash_map::RandomState;
use std::fs::File;
use std::hash::{BuildHasher, Hasher};
use std::io::{BufRead, BufReader, Read, Take};
use std::path::Path;
use std::sync::OnceLock;

/// The content of a file as far as a cache needs it: its length and a hash
/// of its bytes keyed with this process's random key (so no file can be
/// made to collide with another on purpose).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Fingerprint {
    len: u64,
    hash: u64,
}

/// Hashes a byte stream in fixed blocks, so the hash does not depend on how
/// the stream was cut into reads.
struct BlockHasher {
    hasher: std::hash::DefaultHasher,
    block: Box<[u8; 8192]>,
    filled: usize,
    len: u64,
}

impl BlockHasher {
    fn new() -> BlockHasher {
        static KEY: OnceLock<RandomState> = OnceLock::new();
        BlockHasher {
            hasher: KEY.get_or_init(RandomState::new).build_hasher(),
            block: Box::new([0; 8192]),
            filled: 0,
            len: 0,
        }
    }

    fn add(&mut self, mut bytes: &[u8]) {
        self.len += bytes.len() as u64;
        while !bytes.is_empty() {
            let n = bytes.len().min(self.block.len() - self.filled);
            self.block[self.filled..self.filled + n].copy_from_slice(&bytes[..n]);
            self.filled += n;
            bytes = &bytes[n..];
            if self.filled == self.block.len() {
                self.hasher.write(&self.block[..]);
                self.filled = 0;
            }
        }
    }

    fn finish(mut self) -> Fingerprint {
        self.hasher.write(&self.block[..self.filled]);
        self.hasher.write_u64(self.len);
        Fingerprint {
            len: self.len,
            hash: self.hasher.finish(),
        }
    }
}

/// A reader that hashes what passes through it.
struct Hashing<'h, R> {
    inner: R,
    hasher: &'h mut BlockHasher,
}

impl<R: Read> Read for Hashing<'_, R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.hasher.add(&buf[..n]);
        Ok(n)
    }
}

/// The fingerprint of a record file's content, read as the readers read it
/// (a regular file of at most [`MAX_RECORD_BYTES`], never blocking).
pub fn fingerprint(path: &Path) -> Result<Fingerprint, RecordError> {
    let name = path.display().to_string();
    let (file, _) = open_regular(path, &name)?;
    let mut hasher = BlockHasher::new();
    let mut reader = Hashing {
        inner: file,
        hasher: &mut hasher,
    };
    std::io::copy(&mut reader, &mut std::io::sink())
        .map_err(|e| err(&name, 0, format!("cannot read the file: {e}")))?;
    Ok(hasher.finish())
}

impl GroundMotion {
    /// Reads a `.AT2` (by extension, case-insensitive) or CSV file; AT2
    /// values are converted from g to m/s^2 with `g`. Only a regular file is
    /// opened (a FIFO, device or directory is refused before opening, so
    /// nothing blocks), and every size is bounded (see [`crate::limits`]).
    pub fn read(path: &Path, g: f64) -> Result<GroundMotion, RecordError> {
        GroundMotion::read_with_fingerprint(path, g).map(|(gm, _)| gm)
    }

    /// As [`GroundMotion::read`], with the [`fingerprint`] of the bytes it
    /// parsed (hashed as they were read: a file changing meanwhile gives
    /// the fingerprint of what was parsed).
    pub fn read_with_fingerprint(
        path: &Path,
        g: f64,
    ) -> Result<(GroundMotion, Fingerprint), RecordError> {
        let name = path.display().to_string();
        let (file, size) = open_regular(path, &name)?;
        let mut hasher = BlockHasher::new();
        let reader = BufReader::new(Hashing {
            inner: file,
            hasher: &mut hasher,
        });
        let lines = BoundedLines::new(reader, &name);
        let is_at2 = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("at2"));
        let gm = if is_at2 {
            parse_at2(lines, size, &name, g)
        } else {
            parse_csv(lines, &name)
        }?;
        Ok((gm, hasher.finish()))
    }

    /// Parses a single-column file (one acceleration per line, no header, `#`
    /// comments allowed) sampled every `dt` from t = 0; values are multiplied
    /// by `factor` (e.g. g for files in units of g).
    pub fn from_single_column(
        text: &str,
        name: &str,
        dt: f64,
        factor: f64,
    ) -> Result<GroundMotion, RecordError> {
        if !(dt.is_finite() && record_step_allowed(dt, 0.0)) {
            return Err(err(
                name,
                0,
                format!(
                    "dt = {} is not allowed: it must be finite and at least {MIN_RECORD_DT:e} s",
                    Num(dt)
                ),
            ));
        }
        let mut values = Vec::new();
        for line in text_lines(text, name) {
            let (no, line) = line?;
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let v: f64 = line.parse().map_err(|_| {
                err(
                    name,
                    no,
                    format!("expected one number per line, found {}", quote(line)),
                )
            })?;
            push_sample(
                &mut values,
                check_accel(v * factor, name, no, line)?,
                name,
                no,
            )?;
        }
        if values.len() < 2 {
            return Err(err(name, 0, "a record needs at least two samples"));
        }
        if dt * (values.len() - 1) as f64 > MAX_RECORD_TIME {
            return Err(err(
                name,
                0,
                format!("the record lasts more than {MAX_RECORD_TIME:e} s"),
            ));
        }
        uniform_checked(dt, values, name)
    }

    /// Parses CSV `time,accel` text (m/s2); `name` appears in errors.
    pub fn from_csv_text(text: &str, name: &str) -> Result<GroundMotion, RecordError> {
        parse_csv(text_lines(text, name), name)
    }
}

fn err(file: &str, line: usize, message: impl Into<String>) -> RecordError {
    RecordError {
        file: file.to_string(),
        line,
        message: message.into(),
    }
}

/// Opens `path` if it is a regular file of at most [`MAX_RECORD_BYTES`]:
/// checked before opening (a FIFO would block `open`, a device never ends)
/// and again on the open file. Returns the reader and the file's size.
fn open_regular(path: &Path, name: &str) -> Result<(Take<File>, u64), RecordError> {
    let cannot = |e: std::io::Error| err(name, 0, format!("cannot read the file: {e}"));
    let regular = |meta: &std::fs::Metadata| {
        if !meta.is_file() {
            return Err(err(
                name,
                0,
                "is not a regular file (a directory, FIFO or device is never read)",
            ));
        }
        if meta.len() > MAX_RECORD_BYTES {
            return Err(err(
                name,
                0,
                format!(
                    "the file has {} bytes, more than the limit of {MAX_RECORD_BYTES} bytes",
                    meta.len()
                ),
            ));
        }
        Ok(meta.len())
    };
    regular(&std::fs::metadata(path).map_err(cannot)?)?;
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        // Never blocks, should the path have become a FIFO since the check.
        options.custom_flags(libc::O_NONBLOCK);
    }
    let file = options.open(path).map_err(cannot)?;
    let size = regular(&file.metadata().map_err(cannot)?)?;
    // A file growing while it is read still stops at the limit.
    Ok((file.take(MAX_RECORD_BYTES + 1), size))
}

/// Lines of a record, numbered from 1, split at LF with every CR shown as
/// a space (CRLF and CR CR LF files); a line longer than
/// [`MAX_RECORD_LINE`] is an error, found without reading past it.
struct BoundedLines<'a, R: BufRead> {
    reader: R,
    file: &'a str,
    no: usize,
    done: bool,
}

impl<'a, R: BufRead> BoundedLines<'a, R> {
    fn new(reader: R, file: &'a str) -> Self {
        BoundedLines {
            reader,
            file,
            no: 0,
            done: false,
        }
    }
}

impl<R: BufRead> Iterator for BoundedLines<'_, R> {
    type Item = Result<(usize, String), RecordError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        self.no += 1;
        let mut buf = Vec::new();
        let limit = MAX_RECORD_LINE as u64 + 1;
        let read = (&mut self.reader).take(limit).read_until(b'\n', &mut buf);
        match read {
            Err(e) => {
                self.done = true;
                return Some(Err(err(self.file, self.no, format!("cannot read: {e}"))));
            }
            Ok(0) if self.no > 1 => {
                self.done = true;
                return None;
            }
            Ok(_) => {}
        }
        if buf.last() == Some(&b'\n') {
            buf.pop();
        } else if buf.len() > MAX_RECORD_LINE {
            self.done = true;
            return Some(Err(err(
                self.file,
                self.no,
                format!("the line is longer than {MAX_RECORD_LINE} bytes (is this a record file?)"),
            )));
        } else {
            self.done = true; // the last line, without an end of line
        }
        let mut line = String::from_utf8_lossy(&buf).replace('\r', " ");
        if self.no == 1 {
            // A UTF-8 byte-order mark (spreadsheets write one) is no content.
            line = line.trim_start_matches('\u{feff}').to_string();
        }
        Some(Ok((self.no, line)))
    }
}

/// The lines of an in-memory text, as [`BoundedLines`] gives a file's.
fn text_lines<'a>(text: &'a str, file: &'a str) -> BoundedLines<'a, &'a [u8]> {
    BoundedLines::new(text.as_bytes(), file)
}

/// Appends a sample, within [`MAX_RECORD_SAMPLES`] and without aborting
/// when memory runs out.
fn push_sample(values: &mut Vec<f64>, x: f64, file: &str, no: usize) -> Result<(), RecordError> {
    if values.len() >= MAX_RECORD_SAMPLES {
        return Err(err(
            file,
            no,
            format!("the record holds more than {MAX_RECORD_SAMPLES} samples"),
        ));
    }
    if values.len() == values.capacity() {
        values
            .try_reserve(values.len().max(1024))
            .map_err(|_| err(file, no, "out of memory while reading the record"))?;
    }
    values.push(x);
    Ok(())
}

/// `x` if it is a finite acceleration within [`MAX_RECORD_ACCEL`].
fn check_accel(x: f64, file: &str, no: usize, token: &str) -> Result<f64, RecordError> {
    if x.is_finite() && x.abs() <= MAX_RECORD_ACCEL {
        Ok(x)
    } else {
        Err(err(
            file,
            no,
            format!(
                "value {} is not an acceleration: it must be finite and at most {MAX_RECORD_ACCEL:e} m/s2 in magnitude",
                quote(token)
            ),
        ))
    }
}

/// Samples every `dt` from t = 0, allocated without aborting.
fn uniform_checked(dt: f64, accel: Vec<f64>, file: &str) -> Result<GroundMotion, RecordError> {
    let mut time = Vec::new();
    time.try_reserve_exact(accel.len())
        .map_err(|_| err(file, 0, "out of memory while reading the record"))?;
    time.extend((0..accel.len()).map(|i| i as f64 * dt));
    Ok(GroundMotion { time, accel })
}

fn number_after(upper: &str, key: &str) -> Option<f64> {
    let rest = &upper[upper.find(key)? + key.len()..];
    let rest = rest.trim_start().strip_prefix('=')?.trim_start();
    let end = rest
        .find(|c: char| !(c.is_ascii_digit() || matches!(c, '.' | '-' | '+' | 'E')))
        .unwrap_or(rest.len());
    rest[..end].parse().ok()
}

/// Reads NPTS and DT from header line 4, in either PEER form:
/// `NPTS=  5435, DT=  .0100 SEC` or `5435   .0100   NPTS, DT`.
fn npts_dt(line: &str) -> Option<(f64, f64)> {
    let upper = line.to_ascii_uppercase();
    if let (Some(n), Some(dt)) = (number_after(&upper, "NPTS"), number_after(&upper, "DT")) {
        return Some((n, dt));
    }
    let mut nums = upper
        .split(|c: char| c.is_whitespace() || c == ',')
        .filter_map(|t| t.parse::<f64>().ok());
    let (n, dt) = (nums.next()?, nums.next()?);
    (n.fract() == 0.0).then_some((n, dt))
}

/// Checks header line 4's NPTS and DT against the limits and against the
/// file's size (each value takes at least two bytes: a digit and a
/// separator) before anything is allocated.
fn check_header(n: f64, dt: f64, size: u64, file: &str) -> Result<usize, RecordError> {
    let e = |m: String| Err(err(file, 4, m));
    // At least two samples, as a CSV record: one sample is no motion.
    if !(n >= 2.0 && n.fract() == 0.0 && n <= MAX_RECORD_SAMPLES as f64) {
        return e(format!(
            "NPTS = {} is not allowed: it must be an integer from 2 to {MAX_RECORD_SAMPLES}",
            Num(n)
        ));
    }
    if !(record_step_allowed(dt, 0.0) && dt * (n - 1.0) <= MAX_RECORD_TIME) {
        return e(format!(
            "DT = {} is not allowed: it must be at least {MIN_RECORD_DT:e} s, with NPTS DT at most {MAX_RECORD_TIME:e} s",
            Num(dt)
        ));
    }
    if n > (size as f64 + 1.0) / 2.0 {
        return e(format!(
            "NPTS = {} but the file has only {size} bytes: it cannot hold that many values",
            Num(n)
        ));
    }
    Ok(n as usize)
}

fn parse_at2(
    lines: impl Iterator<Item = Result<(usize, String), RecordError>>,
    size: u64,
    file: &str,
    g: f64,
) -> Result<GroundMotion, RecordError> {
    let mut npts_dt_found = None;
    let mut values = Vec::new();
    for line in lines {
        let (no, line) = line?;
        if no < 4 {
            continue;
        }
        if no == 4 {
            let (n, dt) = npts_dt(&line).ok_or_else(|| {
                err(
                    file,
                    4,
                    format!(
                        "expected NPTS and DT in header line 4, found {}",
                        quote(line.trim())
                    ),
                )
            })?;
            let n = check_header(n, dt, size, file)?;
            values
                .try_reserve_exact(n)
                .map_err(|_| err(file, 4, format!("out of memory for NPTS = {n} values")))?;
            npts_dt_found = Some((n, dt));
            continue;
        }
        for token in line.split_whitespace() {
            let v: f64 = token.parse().map_err(|_| {
                err(
                    file,
                    no,
                    format!("expected a number, found {}", quote(token)),
                )
            })?;
            push_sample(&mut values, check_accel(v * g, file, no, token)?, file, no)?;
        }
    }
    let (n, dt) =
        npts_dt_found.ok_or_else(|| err(file, 0, "the file has fewer than 4 header lines"))?;
    if values.len() != n {
        return Err(err(
            file,
            0,
            format!(
                "header line 4 says NPTS = {n} but the file holds {} values",
                values.len()
            ),
        ));
    }
    uniform_checked(dt, values, file)
}

fn parse_csv(
    lines: impl Iterator<Item = Result<(usize, String), RecordError>>,
    file: &str,
) -> Result<GroundMotion, RecordError> {
    let (mut time, mut accel) = (Vec::new(), Vec::new());
    for line in lines {
        let (no, line) = line?;
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line.splitn(3, ',').map(str::trim).collect();
        let parsed: Option<Vec<f64>> = fields.iter().map(|f| f.parse().ok()).collect();
        // A header line has no number in it: a row with a typo in one field is no header.
        let header = || fields.len() == 2 && fields.iter().all(|f| f.parse::<f64>().is_err());
        let row = match parsed {
            Some(r) if r.len() == 2 => r,
            None if time.is_empty() && header() => continue,
            _ => {
                return Err(err(
                    file,
                    no,
                    format!("expected two numbers `time,accel`, found {}", quote(line)),
                ))
            }
        };
        if !(row[0].is_finite() && row[0].abs() <= MAX_RECORD_TIME) {
            return Err(err(
                file,
                no,
                format!(
                    "time {} is not allowed: it must be finite and at most {MAX_RECORD_TIME:e} s in magnitude",
                    quote(fields[0])
                ),
            ));
        }
        let a = check_accel(row[1], file, no, fields[1])?;
        if let Some(&last) = time.last() {
            if !record_step_allowed(row[0] - last, row[0]) {
                return Err(err(
                    file,
                    no,
                    format!(
                        "time {} does not increase by at least {MIN_RECORD_DT:e} s (previous {})",
                        Num(row[0]),
                        Num(last)
                    ),
                ));
            }
        }
        push_sample(&mut time, row[0], file, no)?;
        push_sample(&mut accel, a, file, no)?;
    }
    if time.len() < 2 {
        return Err(err(
            file,
            0,
            "a record needs at least two samples `time,accel`",
        ));
    }
    Ok(GroundMotion { time, accel })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at2(text: &str, name: &str, g: f64) -> Result<GroundMotion, RecordError> {
        parse_at2(text_lines(text, name), text.len() as u64, name, g)
    }

    fn csv(text: &str, name: &str) -> Result<GroundMotion, RecordError> {
        parse_csv(text_lines(text, name), name)
    }

    #[test]
    fn reads_both_header_forms_and_counts_values() {
        let a = "t\nt\nt\nNPTS=    3, DT=   .0100 SEC,\r\n  .1E+00 -.2E+00\r\n .3\r\n";
        let gm = at2(a, "a", 10.0).unwrap();
        assert_eq!(gm.accel, vec![1.0, -2.0, 3.0]);
        assert_eq!(gm.time[2], 0.02);
        let b = "t\r\r\nt\r\r\nt\r\r\n   3    0.0200    NPTS, DT\r\r\n1 2 3\r\r\n";
        assert_eq!(at2(b, "b", 1.0).unwrap().time[1], 0.02);
        let c = "t\nt\nt\nNPTS =   3 , DT =   .020 SEC ,\n1 2\n";
        let e = at2(c, "c.AT2", 1.0).unwrap_err();
        assert!(e.to_string().contains("NPTS = 3 but the file holds 2"));
        let d = "t\nt\nt\nNPTS= 2, DT= .01\n1 x\n";
        assert_eq!(at2(d, "d", 1.0).unwrap_err().line, 5);
    }

    #[test]
    fn single_column_with_its_step() {
        let gm = GroundMotion::from_single_column("# in g\n0.1\n-0.2\r\n0.3\n", "s", 0.02, 10.0)
            .unwrap();
        assert_eq!(gm.accel, vec![1.0, -2.0, 3.0]);
        assert_eq!(gm.time[2], 0.04);
        let e = GroundMotion::from_single_column("0.1\n0.2 0.3\n", "s.txt", 0.01, 1.0).unwrap_err();
        assert_eq!((e.line, e.file.as_str()), (2, "s.txt"));
    }

    #[test]
    fn csv_with_and_without_header() {
        let gm = csv("time,accel\n0,1\n0.5,2\n", "x").unwrap();
        assert_eq!(gm.accel, vec![1.0, 2.0]);
        assert_eq!(gm.piece_at(0.25), (1.5, 2.0, 0.5));
        assert_eq!(gm.piece_at(0.5), (0.0, 0.0, f64::INFINITY));
        let e = csv("0,1\n0.5\n", "y.csv").unwrap_err();
        assert_eq!((e.line, e.file.as_str()), (2, "y.csv"));
        assert_eq!(csv("0,1\n0,2\n", "z").unwrap_err().line, 2);
        // Headers have no number; a first row with a typo (the letter O for a
        // zero) is an error, not a header (a fuzzing master found it dropped).
        assert!(csv("time,accel\ns,m/s2\n0,1\n0.5,2\n", "u").is_ok());
        for bad in ["0,5O\n0.01,5\n0.02,-3\n", "a,b\nc,d\n0.0,X\n0.5,1\n0.7,2\n"] {
            let e = csv(bad, "v").unwrap_err();
            assert!(e.message.contains("expected two numbers"), "{bad:?}: {e:?}");
            assert_eq!(
                e.line,
                bad.lines().position(|l| l.contains('0')).unwrap() + 1
            );
        }
    }
}
