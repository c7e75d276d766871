//! The importer's `fmuResourceLocation`: a `file:` URI of the unzipped FMU's
//! `resources` folder, as a local directory. A pure function of the bytes
//! given (no file system, no working directory), total: every byte sequence
//! gives a directory or a reason, never a panic.
//!
//! Accepted forms (the scheme in any case, `%XX` decoded in host and path):
//! - `file:///abs/path`, `file:/abs/path`, `file://localhost/abs/path`;
//! - Windows: `file:///C:/dir`, `file:/C:/dir`, `file://localhost/C:/dir`,
//!   `file:C:/dir`, `file://C:/dir`, `|` for `:` (`file:///C|/dir`),
//!   backslashes as separators, and shares `file://server/share/dir` or
//!   `file:////server/share/dir` (`\\server\share\dir`).
//!
//! Refused, with the reason: NULL or empty, another scheme (`http:`), a path
//! that is not absolute, a `%` not followed by two hexadecimal digits (also
//! before a multi-byte character: `%1é`), an encoded NUL, a query or fragment
//! (`?`, `#`, which a file URI encodes), on Unix a host other than
//! `localhost`, on Windows a path without a drive or share, or one that is
//! not UTF-8 once decoded.

use std::path::PathBuf;

/// Whose path syntax the location is read for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Style {
    /// POSIX: the path is bytes, absolute from `/`; hosts other than
    /// `localhost` are refused.
    Unix,
    /// Windows: `C:\dir` or `\\server\share\dir`, UTF-8.
    Windows,
}

impl Style {
    /// The style of the platform this library was built for.
    pub const HOST: Style = if cfg!(windows) {
        Style::Windows
    } else {
        Style::Unix
    };
}

/// Longest location quoted in a message (characters).
const MAX_SHOWN: usize = 200;

/// The location as a message shows it: at most `MAX_SHOWN` (200) characters,
/// invalid UTF-8 and control characters shown as `?`.
pub fn shown(location: &[u8]) -> String {
    let text = String::from_utf8_lossy(location);
    let mut out: String = text
        .chars()
        .take(MAX_SHOWN)
        .map(|c| {
            if c.is_control() || c == '\u{fffd}' {
                '?'
            } else {
                c
            }
        })
        .collect();
    if text.chars().nth(MAX_SHOWN).is_some() {
        out.push_str("...");
    }
    out
}

/// Decodes `%XX` (two hexadecimal digits, either case); any other `%` is
/// an error naming its byte offset in `text`, which starts at `offset` of
/// the location.
fn percent_decode(text: &[u8], offset: usize) -> Result<Vec<u8>, String> {
    let hex = |b: u8| (b as char).to_digit(16);
    let mut out = Vec::with_capacity(text.len());
    let mut i = 0;
    while i < text.len() {
        let b = text[i];
        if b == b'%' {
            match (
                text.get(i + 1).and_then(|&x| hex(x)),
                text.get(i + 2).and_then(|&x| hex(x)),
            ) {
                (Some(hi), Some(lo)) => {
                    out.push((hi * 16 + lo) as u8);
                    i += 3;
                    continue;
                }
                _ => {
                    return Err(format!(
                        "it has a `%` at byte {} that is not followed by two hexadecimal digits \
                         (percent-encoding)",
                        offset + i
                    ))
                }
            }
        }
        out.push(b);
        i += 1;
    }
    Ok(out)
}

/// Whether `p` starts with a drive: a letter, then `:` or `|`.
fn has_drive(p: &[u8]) -> bool {
    p.len() >= 2 && p[0].is_ascii_alphabetic() && (p[1] == b':' || p[1] == b'|')
}

/// The directory named by `location` in `style`'s syntax, as bytes (UTF-8
/// for [`Style::Windows`], with backslashes), or why it names none.
pub fn parse(location: &[u8], style: Style) -> Result<Vec<u8>, String> {
    if location.is_empty() {
        return Err("it is empty".into());
    }
    let scheme_ok = location.len() >= 5 && location[..5].eq_ignore_ascii_case(b"file:");
    if !scheme_ok {
        return Err("it is not a `file:` URI (the FMU reads local files only)".into());
    }
    if let Some(i) = location.iter().position(|&b| b == b'?' || b == b'#') {
        return Err(format!(
            "it has a query or fragment (`{}` at byte {i}); a `file:` URI of a folder \
             percent-encodes these characters",
            location[i] as char
        ));
    }
    let windows = style == Style::Windows;
    let is_sep = |b: u8| b == b'/' || (windows && b == b'\\');
    let rest = &location[5..];
    let mut offset = 5;
    // The authority after `//`, if any: empty or `localhost` is this machine.
    let mut host: Vec<u8> = Vec::new();
    let mut path = rest;
    if rest.len() >= 2 && is_sep(rest[0]) && is_sep(rest[1]) {
        let after = &rest[2..];
        let end = after.iter().position(|&b| is_sep(b)).unwrap_or(after.len());
        let authority = percent_decode(&after[..end], offset + 2)?;
        path = &after[end..];
        offset += 2 + end;
        if windows && has_drive(&authority) && authority.len() == 2 {
            // `file://C:/dir`: a drive where the host would be.
            let mut p = authority.clone();
            p.extend_from_slice(&percent_decode(path, offset)?);
            return windows_path(p, Vec::new());
        }
        if !authority.eq_ignore_ascii_case(b"localhost") {
            host = authority;
        }
    }
    let decoded = percent_decode(path, offset)?;
    if decoded.contains(&0) {
        return Err("it has an encoded NUL byte (%00)".into());
    }
    match style {
        Style::Unix => {
            if !host.is_empty() {
                return Err(format!(
                    "it names the host `{}`: only a folder of this machine is read \
                     (file:///path or file://localhost/path)",
                    shown(&host)
                ));
            }
            if decoded.first() != Some(&b'/') {
                return Err("its path is not absolute".into());
            }
            Ok(decoded)
        }
        Style::Windows => windows_path(decoded, host),
    }
}

/// A Windows path from a decoded URI path (separators `/` or `\`) and host.
fn windows_path(decoded: Vec<u8>, host: Vec<u8>) -> Result<Vec<u8>, String> {
    let text = String::from_utf8(decoded)
        .map_err(|_| "its path is not UTF-8 once percent-decoded".to_string())?;
    let host = String::from_utf8(host)
        .map_err(|_| "its host is not UTF-8 once percent-decoded".to_string())?;
    let path = text.replace('/', "\\");
    let trimmed = path.trim_start_matches('\\');
    let leading = path.len() - trimmed.len();
    let share = |server: &str, rest: &str| -> Result<Vec<u8>, String> {
        let mut parts = rest.splitn(2, '\\');
        let name = parts.next().unwrap_or("");
        if server.is_empty() || name.is_empty() {
            return Err("it names a network share without a server or share name".into());
        }
        Ok(format!("\\\\{server}\\{rest}").into_bytes())
    };
    if !host.is_empty() {
        // file://server/share/dir
        return share(&host, trimmed);
    }
    let b = trimmed.as_bytes();
    if has_drive(b) && leading <= 1 {
        let after = &trimmed[2..];
        if !(after.is_empty() || after.starts_with('\\')) {
            return Err(
                "its drive is not followed by a separator (a path relative to that \
                        drive's current folder)"
                    .into(),
            );
        }
        let letter = b[0].to_ascii_uppercase() as char;
        let tail = if after.is_empty() { "\\" } else { after };
        return Ok(format!("{letter}:{tail}").into_bytes());
    }
    if leading >= 2 {
        // file:////server/share/dir (an empty authority and a UNC path)
        let mut parts = trimmed.splitn(2, '\\');
        let server = parts.next().unwrap_or("");
        return share(server, parts.next().unwrap_or(""));
    }
    Err("its path has neither a drive (C:/...) nor a network share (//server/share/...)".into())
}

/// The resources folder of `location` on this platform, or why there is
/// none (NULL is `None`).
pub fn resource_dir(location: Option<&[u8]>) -> Result<PathBuf, String> {
    let location = location.ok_or("it is NULL")?;
    let bytes = parse(location, Style::HOST)?;
    #[cfg(unix)]
    {
        use std::os::unix::ffi::OsStringExt;
        Ok(PathBuf::from(std::ffi::OsString::from_vec(bytes)))
    }
    #[cfg(not(unix))]
    {
        // Windows paths are UTF-8 here (checked by `parse`).
        Ok(PathBuf::from(String::from_utf8_lossy(&bytes).into_owned()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unix(s: &str) -> Result<String, String> {
        parse(s.as_bytes(), Style::Unix).map(|b| String::from_utf8_lossy(&b).into_owned())
    }

    fn win(s: &str) -> Result<String, String> {
        parse(s.as_bytes(), Style::Windows).map(|b| String::from_utf8(b).unwrap())
    }

    #[test]
    fn unix_forms() {
        // Expected: the path of RFC 8089's forms, percent-decoded.
        let ok = [
            ("file:///tmp/fmu/resources", "/tmp/fmu/resources"),
            ("file:/tmp/fmu/resources/", "/tmp/fmu/resources/"),
            ("FILE://localhost/tmp/a%20b", "/tmp/a b"),
            ("file://LocalHost/x", "/x"),
            ("file:///tmp/%C3%A9t%C3%A9", "/tmp/été"),
            ("file:///tmp/été", "/tmp/été"),
            ("file:///tmp/a%2fb", "/tmp/a/b"),
            ("file:////server/share", "//server/share"),
        ];
        for (uri, path) in ok {
            assert_eq!(unix(uri).as_deref(), Ok(path), "{uri}");
        }
        // A decoded byte that is not UTF-8 is a Unix path all the same.
        assert_eq!(
            parse(b"file:///tmp/%E9", Style::Unix),
            Ok(b"/tmp/\xe9".to_vec())
        );
    }

    #[test]
    fn windows_forms() {
        let ok = [
            (
                "file:///C:/Users/a%20b/resources",
                "C:\\Users\\a b\\resources",
            ),
            ("file:/c:/dir", "C:\\dir"),
            ("file://localhost/D:/dir/", "D:\\dir\\"),
            ("file:C:/dir", "C:\\dir"),
            ("file://C:/dir", "C:\\dir"),
            ("file:///C|/dir", "C:\\dir"),
            ("file:///C:\\dir\\sub", "C:\\dir\\sub"),
            ("file:///C:", "C:\\"),
            (
                "file://server/share/fmu/resources",
                "\\\\server\\share\\fmu\\resources",
            ),
            ("file:////server/share/dir", "\\\\server\\share\\dir"),
            ("file://srv%2Dx/sh/d", "\\\\srv-x\\sh\\d"),
            ("file:///C:/%E6%97%A5%E6%9C%AC", "C:\\日本"),
        ];
        for (uri, path) in ok {
            assert_eq!(win(uri).as_deref(), Ok(path), "{uri}");
        }
        assert_refused(
            Style::Windows,
            &[
                ("file:///dir/resources", "neither a drive"),
                ("file:relative/dir", "neither a drive"),
                ("file:C:dir", "not followed by a separator"),
                ("file://server", "without a server or share"),
                ("file:///C:/%E9t%E9", "not UTF-8"),
            ],
        );
    }

    /// Each location refused in `style` with a reason containing its text.
    fn assert_refused(style: Style, cases: &[(&str, &str)]) {
        for (uri, why) in cases {
            let e = parse(uri.as_bytes(), style).unwrap_err();
            assert!(e.contains(why), "{uri}: {e}");
        }
    }

    #[test]
    fn unusable_locations_are_named() {
        let cases = [
            ("", "empty"),
            ("http://example.com/resources", "not a `file:` URI"),
            ("file:", "not absolute"),
            ("file:relative/path", "not absolute"),
            ("file://server/share/dir", "names the host `server`"),
            ("file:///tmp/resources%1é", "byte 21"),
            ("file:///tmp/%", "byte 12"),
            ("file:///tmp/%4", "byte 12"),
            ("file:///tmp/%zz", "byte 12"),
            ("file:///tmp/a%00b", "NUL"),
            ("file:///tmp/a?x=1", "query or fragment"),
            ("file:///tmp/a#frag", "query or fragment"),
        ];
        assert_refused(Style::Unix, &cases);
        assert_eq!(resource_dir(None).unwrap_err(), "it is NULL");
        let long = format!("file:///{}", "é".repeat(500));
        assert!(shown(long.as_bytes()).chars().count() <= MAX_SHOWN + 3);
        assert_eq!(shown(b"a\x00\xffb"), "a??b");
    }

    #[test]
    fn every_byte_sequence_gives_a_folder_or_a_reason() {
        // Random bytes, biased to the characters the parser looks at; both
        // styles; no panic, and an accepted Windows path is UTF-8.
        let alphabet: &[u8] = b"file:/\\%C|?#lohst0aF9\xc3\xa9\xe9 .";
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for case in 0..200_000 {
            let len = (next() % 24) as usize;
            let mut bytes: Vec<u8> = if case % 2 == 0 {
                b"file:".to_vec()
            } else {
                Vec::new()
            };
            for _ in 0..len {
                let r = next();
                bytes.push(if r % 4 == 0 {
                    (r >> 8) as u8
                } else {
                    alphabet[(r >> 8) as usize % alphabet.len()]
                });
            }
            let _ = parse(&bytes, Style::Unix);
            if let Ok(p) = parse(&bytes, Style::Windows) {
                assert!(String::from_utf8(p).is_ok());
            }
            let _ = shown(&bytes);
        }
    }
}
