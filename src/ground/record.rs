//! Ground-motion records: PEER `.AT2` files (units of g) and two-column CSV
//! `time,accel` tables (m/s^2), and driving a simulator through one.
//!
//! A record is a table of samples; between samples the acceleration is
//! linear, before the first and after the last it is zero. An `.AT2` file's
//! first value is at t = 0 and the n-th at n DT.

use crate::limits::{
    quote, MAX_RECORD_ACCEL, MAX_RECORD_BYTES, MAX_RECORD_LINE, MAX_RECORD_SAMPLES,
    MAX_RECORD_TIME, MIN_RECORD_DT,
};
use crate::physics::engine::{Excitation, SimError};
use crate::physics::solver::Stepper;
use std::fmt;
use std::fs::File;
use std::io::{BufRead, BufReader, Read, Take};
use std::path::Path;

/// A tabulated ground acceleration (m/s^2) at increasing times (s).
#[derive(Clone, Debug, PartialEq)]
pub struct GroundMotion {
    /// Sample times (s), increasing.
    pub time: Vec<f64>,
    /// Accelerations at those times (m/s2).
    pub accel: Vec<f64>,
}

/// A record that could not be read: which file, which line, what was wrong.
#[derive(Clone, Debug, PartialEq)]
pub struct RecordError {
    /// The file's name as given.
    pub file: String,
    /// 1-based line number, 0 when the problem is not on one line.
    pub line: usize,
    /// What was wrong.
    pub message: String,
}

impl fmt::Display for RecordError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line > 0 {
            write!(f, "{}:{}: {}", self.file, self.line, self.message)
        } else {
            write!(f, "{}: {}", self.file, self.message)
        }
    }
}

impl std::error::Error for RecordError {}

impl GroundMotion {
    /// Samples every `dt` from t = 0.
    pub fn uniform(dt: f64, accel: Vec<f64>) -> GroundMotion {
        let time = (0..accel.len()).map(|i| i as f64 * dt).collect();
        GroundMotion { time, accel }
    }

    /// Reads a `.AT2` (by extension, case-insensitive) or CSV file; AT2
    /// values are converted from g to m/s^2 with `g`. Only a regular file is
    /// opened (a FIFO, device or directory is refused before opening, so
    /// nothing blocks), and every size is bounded (see [`crate::limits`]).
    pub fn read(path: &Path, g: f64) -> Result<GroundMotion, RecordError> {
        let name = path.display().to_string();
        let (reader, size) = open_regular(path, &name)?;
        let lines = BoundedLines::new(reader, &name);
        let is_at2 = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("at2"));
        if is_at2 {
            parse_at2(lines, size, &name, g)
        } else {
            parse_csv(lines, &name)
        }
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
        if !(dt > 0.0 && dt.is_finite()) {
            return Err(err(name, 0, format!("dt = {dt} must be positive")));
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
        uniform_checked(dt, values, name)
    }

    /// Parses CSV `time,accel` text (m/s2); `name` appears in errors.
    pub fn from_csv_text(text: &str, name: &str) -> Result<GroundMotion, RecordError> {
        parse_csv(text_lines(text, name), name)
    }

    /// Duration covered by the samples (time of the last one).
    pub fn duration(&self) -> f64 {
        self.time.last().copied().unwrap_or(0.0)
    }

    /// Number of samples at times in `(t0, t1]`.
    pub fn samples_in(&self, t0: f64, t1: f64) -> usize {
        let after = |t: f64| self.time.partition_point(|&x| x <= t);
        after(t1).saturating_sub(after(t0))
    }

    /// Largest absolute acceleration.
    pub fn pga(&self) -> f64 {
        self.accel.iter().fold(0.0, |m, a| m.max(a.abs()))
    }

    /// Index of the first sample strictly after `t`: guessed from the mean
    /// spacing (exact for uniform records), checked, else binary search.
    fn first_after(&self, t: f64) -> usize {
        let n = self.time.len();
        if n >= 2 {
            let span = self.time[n - 1] - self.time[0];
            let guess = ((t - self.time[0]) / span * (n - 1) as f64).floor() + 1.0;
            if guess >= 1.0 && guess < n as f64 {
                let i = guess as usize;
                if self.time[i - 1] <= t && t < self.time[i] {
                    return i;
                }
            }
        }
        self.time.partition_point(|&x| x <= t)
    }

    /// The linear piece that holds at `t` (looking forward): its value at
    /// `t`, its slope, and where it ends (the next sample, or infinity).
    pub fn piece_at(&self, t: f64) -> (f64, f64, f64) {
        self.piece_before(self.first_after(t), t)
    }

    /// The piece that holds at `t` when `i` is the first sample after `t`.
    #[inline]
    fn piece_before(&self, i: usize, t: f64) -> (f64, f64, f64) {
        let n = self.time.len();
        if i == 0 {
            let end = self.time.first().copied().unwrap_or(f64::INFINITY);
            return (0.0, 0.0, end);
        }
        if i >= n {
            return (0.0, 0.0, f64::INFINITY);
        }
        let (t0, t1) = (self.time[i - 1], self.time[i]);
        let slope = (self.accel[i] - self.accel[i - 1]) / (t1 - t0);
        (self.accel[i - 1] + slope * (t - t0), slope, t1)
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
fn open_regular(path: &Path, name: &str) -> Result<(BufReader<Take<File>>, u64), RecordError> {
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
    Ok((BufReader::new(file.take(MAX_RECORD_BYTES + 1)), size))
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
        let line = String::from_utf8_lossy(&buf).replace('\r', " ");
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
    if !(n >= 1.0 && n.fract() == 0.0 && n <= MAX_RECORD_SAMPLES as f64) {
        return e(format!(
            "NPTS = {n} is not allowed: it must be an integer from 1 to {MAX_RECORD_SAMPLES}"
        ));
    }
    if !(dt >= MIN_RECORD_DT && dt * (n - 1.0) <= MAX_RECORD_TIME) {
        return e(format!(
            "DT = {dt} is not allowed: it must be at least {MIN_RECORD_DT:e} s, with NPTS DT at most {MAX_RECORD_TIME:e} s"
        ));
    }
    if n > (size as f64 + 1.0) / 2.0 {
        return e(format!(
            "NPTS = {n} but the file has only {size} bytes: it cannot hold that many values"
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
        let row = match parsed {
            Some(r) if r.len() == 2 => r,
            None if time.is_empty() && fields.len() == 2 => continue, // header line
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
            if row[0] - last < MIN_RECORD_DT {
                return Err(err(
                    file,
                    no,
                    format!(
                        "time {} does not increase by at least {MIN_RECORD_DT:e} s (previous {last})",
                        row[0]
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

/// Drives `sim` from its current time to `t_end` under `scale * record`
/// plus `extra` (linear from the current time), splitting at every sample
/// so that each piece is linear.
pub fn advance_with_record<S: Stepper>(
    sim: &mut S,
    t_end: f64,
    record: &GroundMotion,
    scale: f64,
    extra: &Excitation,
) -> Result<(), SimError> {
    let t_start = sim.time();
    let mut t = t_start;
    let mut done = false;
    // First sample after `t`, carried from piece to piece.
    let mut next_sample = record.first_after(t);
    let pieces = std::iter::from_fn(move || {
        if done {
            return None;
        }
        while next_sample < record.time.len() && record.time[next_sample] <= t {
            next_sample += 1;
        }
        let (a, slope, piece_end) = record.piece_before(next_sample, t);
        let t1 = piece_end.min(t_end);
        let dt = t - t_start;
        let exc = Excitation {
            ag: scale * a + extra.ag + extra.ag_rate * dt,
            ag_rate: scale * slope + extra.ag_rate,
            fext: extra.fext + extra.fext_rate * dt,
            fext_rate: extra.fext_rate,
        };
        t = t1;
        done = t1 >= t_end;
        Some((t1, exc))
    });
    sim.advance_pieces(pieces)
}

/// Runs a whole record from the simulator's current time to the record's end.
pub fn run<S: Stepper>(sim: &mut S, record: &GroundMotion, scale: f64) -> Result<(), SimError> {
    advance_with_record(
        sim,
        record.duration(),
        record,
        scale,
        &Excitation::default(),
    )
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
    }

    /// Collects the pieces it is given.
    struct Recorder {
        t: f64,
        pieces: Vec<(f64, f64, f64)>,
    }

    impl crate::physics::solver::Stepper for Recorder {
        fn time(&self) -> f64 {
            self.t
        }
        fn advance(&mut self, t_end: f64, exc: &Excitation) -> Result<(), SimError> {
            self.pieces.push((t_end, exc.ag, exc.ag_rate));
            self.t = t_end;
            Ok(())
        }
    }

    #[test]
    fn a_record_is_fed_piece_by_piece_as_piece_at_gives_it() {
        // Expected values: `piece_at` (the lookup from scratch) at each
        // piece's start, from a start between samples to an end past them.
        let gm = GroundMotion {
            time: vec![0.0, 0.1, 0.25, 0.3, 0.5],
            accel: vec![1.0, -2.0, 0.5, 4.0, 0.0],
        };
        let mut rec = Recorder {
            t: 0.05,
            pieces: Vec::new(),
        };
        advance_with_record(&mut rec, 0.7, &gm, 2.0, &Excitation::default()).unwrap();
        let mut t = 0.05;
        let mut expected = Vec::new();
        while t < 0.7 {
            let (a, slope, end) = gm.piece_at(t);
            let end = end.min(0.7);
            expected.push((end, 2.0 * a, 2.0 * slope));
            t = end;
        }
        assert_eq!(rec.pieces, expected);
        assert_eq!(rec.pieces.len(), 5);
    }
}
