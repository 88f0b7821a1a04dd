//! Reader for `.bpt` files: lists of tensor-product Bézier patches, the format of Newell's
//! teaset (Utah teapot, teacup, teaspoon), whose models are z-up.
//!
//! # Format
//!
//! Plain ASCII, tokens separated by any whitespace (blank lines and `\r\n` line ends are
//! fine; there are no comments):
//!
//! ```text
//! N                  number of patches, N ≥ 1
//! du dv              degrees of patch 0, each 0..=15
//! x y z              (du+1)·(dv+1) control points, row-major:
//! ...                row i = 0..=du (along u), column j = 0..=dv (along v)
//! du dv              degrees of patch 1
//! ...
//! ```
//!
//! Nothing but whitespace may follow the last patch. Coordinates are read with Rust's `f64`
//! syntax, so `nan` and `inf` are read as numbers and then rejected as non-finite with the line
//! of the offending coordinate.
//!
//! # Errors
//!
//! Every failure is a [`LoadError`] naming the file and, where it applies, the 1-based line
//! (patch and control-point numbers are 0-based, as in [`crate::model::Scene::patches`]):
//! unreadable file ([`LoadError::Io`]), NUL bytes or invalid UTF-8 ([`LoadError::NotText`],
//! with the byte offset), empty or whitespace-only file ([`LoadError::Empty`]), zero patches
//! ([`LoadError::NoPatches`]), a token that is not a number, a negative or out-of-range count,
//! an unexpected end of file or trailing data ([`LoadError::Parse`]), and invalid patches —
//! degree above `MAX_DEGREE`, NaN or infinite coordinate, a coordinate beyond
//! ±`MAX_COORDINATE` (f32's range for squared lengths: such a model cannot be framed or
//! drawn, so it is an error rather than a warning), all control points equal
//! ([`LoadError::Patch`]).
//!
//! The reader never panics and never allocates in proportion to a count it has not yet seen
//! backed by data: the patch count is capped at `MAX_PATCHES` and only reserves a little
//! space, and a degree above `MAX_DEGREE` is reported from the patch header before any control
//! point is read.

use std::path::Path;

use glam::DVec3;

use super::LoadError;
use crate::model::bezier::{BezierPatch, MAX_COORDINATE, MAX_DEGREE, PatchError};

/// Largest patch count accepted in a file header.
pub(crate) const MAX_PATCHES: u64 = 10_000_000;

/// Reads and parses a `.bpt` file.
pub fn read(path: &Path) -> Result<Vec<BezierPatch>, LoadError> {
    let bytes = std::fs::read(path).map_err(|source| LoadError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse(&bytes, path)
}

/// Writes `count` patches in the format above: numbers in Rust's shortest round-trip `f64`
/// form, so reading the file back gives exactly the same control points. Streams: nothing but
/// the patch being written is held. `count` must be the number of patches `patches` yields
/// (the header comes first).
pub fn write<I>(out: &mut impl std::io::Write, count: usize, patches: I) -> std::io::Result<()>
where
    I: IntoIterator,
    I::Item: std::borrow::Borrow<BezierPatch>,
{
    use std::borrow::Borrow;
    writeln!(out, "{count}")?;
    let mut written = 0;
    for p in patches {
        let p = p.borrow();
        let (du, dv) = p.degree();
        writeln!(out, "{du} {dv}")?;
        for c in p.control_points() {
            writeln!(out, "{} {} {}", c.x, c.y, c.z)?;
        }
        written += 1;
    }
    if written != count {
        return Err(std::io::Error::other(format!(
            "{written} patches written after a header of {count}"
        )));
    }
    Ok(())
}

/// Parses the contents of a `.bpt` file; `path` is only used in error messages.
pub fn parse(bytes: &[u8], path: &Path) -> Result<Vec<BezierPatch>, LoadError> {
    let text = as_text(bytes, path)?;
    let mut r = Reader {
        path,
        tokens: Tokens::new(text),
    };

    let Some((line, token)) = r.tokens.next() else {
        return Err(LoadError::Empty {
            path: path.to_path_buf(),
        });
    };
    let n = r.count(line, token, || "the number of patches".to_owned(), None)?;
    if n == 0 {
        return Err(LoadError::NoPatches {
            path: path.to_path_buf(),
        });
    }
    if n > MAX_PATCHES {
        return Err(r.parse_error(
            line,
            format!("the file declares {n} patches, more than the limit of {MAX_PATCHES}"),
        ));
    }
    // Reserve only a little: the count is not yet backed by data.
    let mut patches = Vec::with_capacity(n.min(1024) as usize);

    let mut previous_points = None;
    for k in 0..n {
        let what_du = || format!("the u degree of patch {k} (the file declares {n} patches)");
        let (header_line, token) = r.expect(what_du)?;
        let du = r.count(
            header_line,
            token,
            what_du,
            previous_points.map(|c| (k - 1, c)),
        )?;
        let what_dv = || format!("the v degree of patch {k}");
        let (line, token) = r.expect(what_dv)?;
        let dv = r.count(line, token, what_dv, None)?;

        let patch_error = |line, source| LoadError::Patch {
            path: path.to_path_buf(),
            line,
            patch: k as usize,
            source,
        };
        let (du, dv) = (to_usize(du), to_usize(dv));
        if du > MAX_DEGREE || dv > MAX_DEGREE {
            return Err(patch_error(
                header_line,
                PatchError::DegreeTooHigh { du, dv },
            ));
        }

        let count = (du + 1) * (dv + 1);
        let mut ctrl = Vec::with_capacity(count);
        for index in 0..count {
            let mut p = [0.0; 3];
            let mut non_finite_line = None;
            for (c, axis) in ["x", "y", "z"].into_iter().enumerate() {
                let what =
                    || format!("the {axis} coordinate of control point {index} of patch {k}");
                let (line, token) = r.expect(what)?;
                p[c] = token.parse::<f64>().map_err(|_| {
                    r.parse_error(
                        line,
                        format!("expected a number for {}, found {}", what(), show(token)),
                    )
                })?;
                let bad = !p[c].is_finite() || p[c].abs() > MAX_COORDINATE;
                if bad && non_finite_line.is_none() {
                    non_finite_line = Some(line);
                }
            }
            if let Some(line) = non_finite_line {
                let [x, y, z] = p;
                let e = if p.iter().all(|c| c.is_finite()) {
                    PatchError::TooFar { index, x, y, z }
                } else {
                    PatchError::NonFinite { index, x, y, z }
                };
                return Err(patch_error(line, e));
            }
            ctrl.push(DVec3::from_array(p));
        }
        let patch = BezierPatch::new(du, dv, ctrl).map_err(|e| patch_error(header_line, e))?;
        patches.push(patch);
        previous_points = Some(count);
    }

    if let Some((line, token)) = r.tokens.next() {
        return Err(r.parse_error(
            line,
            format!(
                "unexpected {} after the last of the {n} patches the file declares",
                show(token)
            ),
        ));
    }
    Ok(patches)
}

/// The bytes as text, or where they stop being text. A leading UTF-8 byte-order mark is skipped.
fn as_text<'a>(bytes: &'a [u8], path: &Path) -> Result<&'a str, LoadError> {
    let not_text = |offset, what| LoadError::NotText {
        path: path.to_path_buf(),
        offset,
        what,
    };
    let nul = bytes.iter().position(|&b| b == 0);
    match std::str::from_utf8(bytes) {
        Ok(text) => match nul {
            Some(offset) => Err(not_text(offset, "NUL byte")),
            None => Ok(text.strip_prefix('\u{feff}').unwrap_or(text)),
        },
        Err(e) => match nul {
            Some(offset) if offset < e.valid_up_to() => Err(not_text(offset, "NUL byte")),
            _ => Err(not_text(e.valid_up_to(), "invalid UTF-8")),
        },
    }
}

/// A degree as `usize`, saturating (anything that does not fit is above [`MAX_DEGREE`] anyway).
fn to_usize(n: u64) -> usize {
    usize::try_from(n).unwrap_or(usize::MAX)
}

/// A token quoted for an error message, shortened if long.
fn show(token: &str) -> String {
    const MAX_CHARS: usize = 40;
    match token.char_indices().nth(MAX_CHARS) {
        Some((cut, _)) => format!("{:?}…", &token[..cut]),
        None => format!("{token:?}"),
    }
}

/// Whitespace-separated tokens with their 1-based line numbers.
struct Tokens<'a> {
    lines: std::iter::Enumerate<std::str::Split<'a, char>>,
    current: std::str::SplitAsciiWhitespace<'a>,
    /// Line of `current`.
    line: usize,
    /// Line of the last token returned (1 before any).
    last_line: usize,
}

impl<'a> Tokens<'a> {
    fn new(text: &'a str) -> Self {
        Tokens {
            lines: text.split('\n').enumerate(),
            current: "".split_ascii_whitespace(),
            line: 0,
            last_line: 1,
        }
    }

    fn next(&mut self) -> Option<(usize, &'a str)> {
        loop {
            if let Some(token) = self.current.next() {
                self.last_line = self.line;
                return Some((self.line, token));
            }
            let (i, line) = self.lines.next()?;
            self.line = i + 1;
            self.current = line.split_ascii_whitespace();
        }
    }
}

struct Reader<'a> {
    path: &'a Path,
    tokens: Tokens<'a>,
}

impl<'a> Reader<'a> {
    fn parse_error(&self, line: usize, reason: String) -> LoadError {
        LoadError::Parse {
            path: self.path.to_path_buf(),
            line,
            reason,
        }
    }

    /// The next token, or an end-of-file error at the line of the last token.
    fn expect(&mut self, what: impl FnOnce() -> String) -> Result<(usize, &'a str), LoadError> {
        match self.tokens.next() {
            Some(t) => Ok(t),
            None => Err(self.parse_error(
                self.tokens.last_line,
                format!("unexpected end of file: expected {}", what()),
            )),
        }
    }

    /// A non-negative whole number. `after` = (index, control-point count) of the previous
    /// patch when `token` should start a patch header, to hint at a miscounted patch.
    fn count(
        &self,
        line: usize,
        token: &str,
        what: impl FnOnce() -> String,
        after: Option<(u64, usize)>,
    ) -> Result<u64, LoadError> {
        use std::num::IntErrorKind;
        let reason = match token.parse::<i64>() {
            Ok(n) => match u64::try_from(n) {
                Ok(n) => return Ok(n),
                Err(_) => format!("{} must not be negative, found {}", what(), show(token)),
            },
            Err(e) if *e.kind() == IntErrorKind::PosOverflow => {
                format!("{} is out of range, found {}", what(), show(token))
            }
            Err(e) if *e.kind() == IntErrorKind::NegOverflow => {
                format!("{} must not be negative, found {}", what(), show(token))
            }
            Err(_) => {
                let mut reason = format!(
                    "expected a whole number for {}, found {}",
                    what(),
                    show(token)
                );
                if let Some((prev, points)) = after.filter(|_| token.parse::<f64>().is_ok()) {
                    reason += &format!(
                        " (a patch starts with its degrees `du dv`: does patch {prev} have more \
                         than {points} control points?)"
                    );
                }
                reason
            }
        };
        Err(self.parse_error(line, reason))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Control point (i, j) of patch `k` at (k, i, j) + fractions, so order errors show.
    fn point(k: usize, i: usize, j: usize) -> DVec3 {
        DVec3::new(k as f64 + 0.5, i as f64 + 0.25, j as f64 - 0.125)
    }

    fn write_bpt(degrees: &[(usize, usize)], eol: &str) -> String {
        let mut s = format!("{}{eol}", degrees.len());
        for (k, &(du, dv)) in degrees.iter().enumerate() {
            s += &format!("{du} {dv}{eol}");
            for i in 0..=du {
                for j in 0..=dv {
                    let p = point(k, i, j);
                    s += &format!("{} {} {}{eol}", p.x, p.y, p.z);
                }
            }
        }
        s
    }

    #[test]
    fn written_patches_read_back_exactly() {
        let odd = [0.1, -1.0 / 3.0, 1e-300, 12345.678901234567, -0.0, 7.3e18];
        let patches: Vec<BezierPatch> = [(1, 2), (3, 3)]
            .iter()
            .enumerate()
            .map(|(k, &(du, dv))| {
                let ctrl = (0..(du + 1) * (dv + 1))
                    .map(|i| {
                        let o = odd[(i + k) % odd.len()];
                        DVec3::new(o, i as f64 + o, k as f64 - o)
                    })
                    .collect();
                BezierPatch::new(du, dv, ctrl).expect("valid")
            })
            .collect();
        let mut text = Vec::new();
        write(&mut text, 2, &patches).expect("written");
        let back = parse(&text, Path::new("w.bpt")).expect("read back");
        assert_eq!(back, patches);
        // A wrong count is an error, not a file that does not read back.
        assert!(write(&mut Vec::new(), 3, &patches).is_err());
    }

    fn check_row_major(patches: &[BezierPatch], degrees: &[(usize, usize)]) {
        assert_eq!(patches.len(), degrees.len());
        for (k, (patch, &(du, dv))) in patches.iter().zip(degrees).enumerate() {
            assert_eq!(patch.degree(), (du, dv));
            let ctrl = patch.control_points();
            assert_eq!(ctrl.len(), (du + 1) * (dv + 1));
            for i in 0..=du {
                for j in 0..=dv {
                    assert_eq!(
                        ctrl[i * (dv + 1) + j],
                        point(k, i, j),
                        "patch {k} point ({i},{j})"
                    );
                }
            }
        }
    }

    fn parse_str(text: &str) -> Result<Vec<BezierPatch>, LoadError> {
        parse(text.as_bytes(), Path::new("test.bpt"))
    }

    #[test]
    fn reads_bicubic_patch_row_major() {
        let degrees = [(3, 3)];
        let patches = parse_str(&write_bpt(&degrees, "\n")).expect("valid file");
        check_row_major(&patches, &degrees);
    }

    #[test]
    fn reads_degree_2_by_5_patch_row_major() {
        let degrees = [(2, 5)];
        let patches = parse_str(&write_bpt(&degrees, "\n")).expect("valid file");
        check_row_major(&patches, &degrees);
    }

    #[test]
    fn reads_degree_15_by_15_patch_row_major() {
        let degrees = [(15, 15)];
        let patches = parse_str(&write_bpt(&degrees, "\n")).expect("valid file");
        check_row_major(&patches, &degrees);
    }

    #[test]
    fn reads_mixed_degrees_with_crlf_and_blank_lines() {
        let degrees = [(3, 3), (0, 1), (1, 0), (5, 2), (15, 4)];
        let text = write_bpt(&degrees, "\r\n\r\n  \t\r\n");
        let patches = parse_str(&text).expect("valid file");
        check_row_major(&patches, &degrees);
    }

    #[test]
    fn tokens_need_not_follow_lines() {
        let patches = parse_str("1 1 1 0 0 0 0 1 0 1 0 0 1 1 1").expect("valid file");
        assert_eq!(patches[0].control_points()[3], DVec3::ONE);
    }

    #[test]
    fn skips_byte_order_mark() {
        let text = format!("\u{feff}{}", write_bpt(&[(1, 1)], "\n"));
        assert!(parse_str(&text).is_ok());
    }

    #[test]
    fn end_of_file_points_at_last_token_line() {
        let err = parse_str("1\n1 1\n0 0 0\n0 1 0\n\n\n").expect_err("too short");
        assert!(matches!(err, LoadError::Parse { line: 4, .. }), "{err}");
        let msg = err.to_string();
        assert!(
            msg.contains("end of file")
                && msg.contains("x coordinate of control point 2 of patch 0"),
            "{msg}"
        );
    }

    #[test]
    fn extra_control_point_hints_at_miscount() {
        let text =
            "2\n1 1\n0 0 0\n0 1 0\n1 0 0\n1 1 1\n0.5 0.5 0.5\n1 1\n0 0 0\n0 1 0\n1 0 0\n1 1 1\n";
        let err = parse_str(text).expect_err("extra point in patch 0");
        assert!(
            err.to_string()
                .contains("does patch 0 have more than 4 control points"),
            "{err}"
        );
    }

    #[test]
    fn huge_degree_is_reported_before_reading_points() {
        let err = parse_str("1\n3 99999999999\n").expect_err("degree too high");
        assert!(
            matches!(
                err,
                LoadError::Patch {
                    line: 2,
                    patch: 0,
                    source: PatchError::DegreeTooHigh { .. },
                    ..
                }
            ),
            "{err}"
        );
    }

    #[test]
    fn long_tokens_are_shortened_in_messages() {
        let long = "x".repeat(10_000);
        let err = parse_str(&format!("1\n1 1\n{long} 0 0\n")).expect_err("not a number");
        assert!(err.to_string().len() < 300, "{err}");
    }
}
