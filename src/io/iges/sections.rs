//! The fixed-format file structure of IGES 5.3 (§2.1): 80-column lines, the section letter
//! (S, G, D, P, T) in column 73 and a sequence number in columns 74–80; the global section's
//! free-format parameters (§2.2.3) with its parameter and record delimiters (columns 1–72); the
//! parameter data of an entity (columns 1–64 of its P lines, §2.2.4.4); Hollerith strings
//! (`nH…`) and reals with `D` exponents. The compressed ASCII form (`C` section) and the binary
//! form are not read.
//!
//! Every count the file states is checked against the lines the file holds before anything is
//! sized by it.

use super::IgesError;

/// One parameter of a free-format record.
#[derive(Clone, Debug, PartialEq)]
pub enum Param {
    /// Nothing between two delimiters: the parameter's default.
    Empty,
    Int(i64),
    Real(f64),
    Str(String),
}

impl Param {
    /// The value as a real (integers too).
    pub fn real(&self) -> Option<f64> {
        match self {
            Param::Int(i) => Some(*i as f64),
            Param::Real(r) => Some(*r),
            _ => None,
        }
    }

    /// The value as an integer (a real with an integral value too, as some writers write
    /// `3.` for a count).
    pub fn int(&self) -> Option<i64> {
        match self {
            Param::Int(i) => Some(*i),
            Param::Real(r) if r.fract() == 0.0 && r.abs() < 1e15 => Some(*r as i64),
            _ => None,
        }
    }

    pub fn string(&self) -> Option<&str> {
        match self {
            Param::Str(s) => Some(s),
            _ => None,
        }
    }
}

/// The global section's delimiters and the parameters the reader uses.
#[derive(Clone, Debug)]
pub struct Global {
    pub param_delim: u8,
    pub record_delim: u8,
    /// All global parameters, 1-based as in the standard (index 0 unused, `Empty`).
    pub params: Vec<Param>,
}

impl Global {
    /// Parameter `n` (1-based), `Empty` when absent.
    pub fn get(&self, n: usize) -> &Param {
        self.params.get(n).unwrap_or(&Param::Empty)
    }

    /// Millimetres per model unit, from the units flag (parameter 14) and name (15); `None`
    /// when the flag is unknown.
    pub(crate) fn unit_mm(&self) -> Option<f64> {
        let by_name = |name: &str| -> Option<f64> {
            Some(match name.trim().to_ascii_uppercase().as_str() {
                "IN" | "INCH" => 25.4,
                "MM" => 1.0,
                "FT" => 304.8,
                "MI" => 1_609_344.0,
                "M" => 1000.0,
                "KM" => 1_000_000.0,
                "MIL" => 0.0254,
                "UM" => 0.001,
                "CM" => 10.0,
                "UIN" => 0.0000254,
                _ => return None,
            })
        };
        match self.get(14).int() {
            Some(1) => Some(25.4),
            Some(2) => Some(1.0),
            Some(3) => by_name(self.get(15).string()?),
            Some(4) => Some(304.8),
            Some(5) => Some(1_609_344.0),
            Some(6) => Some(1000.0),
            Some(7) => Some(1_000_000.0),
            Some(8) => Some(0.0254),
            Some(9) => Some(0.001),
            Some(10) => Some(10.0),
            Some(11) => Some(0.0000254),
            // Absent: the standard's default is inches, but the name may say otherwise.
            _ => self.get(15).string().and_then(by_name),
        }
    }
}

/// The lines of an IGES file by section, each its 80 bytes.
#[derive(Debug)]
pub struct Sections<'a> {
    pub global: Global,
    /// Directory entry lines (pairs), with their 1-based file line numbers.
    pub directory: Vec<(&'a [u8], usize)>,
    /// Parameter data lines, with their 1-based file line numbers.
    pub parameter: Vec<(&'a [u8], usize)>,
}

/// Splits the file into its sections and checks their order, sequence numbers and the
/// terminate section's counts.
pub fn split(bytes: &[u8]) -> Result<Sections<'_>, IgesError> {
    let mut by: [Vec<(&[u8], usize)>; 5] = Default::default();
    const ORDER: &[u8; 5] = b"SGDPT";
    let mut last = 0usize;
    for (i, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let line = i + 1;
        let l = raw.strip_suffix(b"\r").unwrap_or(raw);
        if l.iter().all(|b| b.is_ascii_whitespace()) {
            continue;
        }
        if let Some(k) = l.iter().position(|b| !b.is_ascii() || *b == 0) {
            return Err(IgesError::Section {
                line,
                reason: format!("byte {} is not ASCII text", k + 1),
            });
        }
        if l.len() != 80 {
            return Err(IgesError::Section {
                line,
                reason: format!(
                    "{} columns; fixed-format IGES lines have 80 (section letter in column 73)",
                    l.len()
                ),
            });
        }
        let Some(section) = ORDER.iter().position(|&c| c == l[72]) else {
            let what = if l[72] == b'C' || l[72] == b'B' {
                "compressed or binary IGES is not supported"
            } else {
                "not a section letter (S, G, D, P, T)"
            };
            return Err(IgesError::Section {
                line,
                reason: format!("column 73 holds {:?}: {what}", l[72] as char),
            });
        };
        if section < last {
            return Err(IgesError::Section {
                line,
                reason: format!(
                    "section {} after section {}",
                    ORDER[section] as char, ORDER[last] as char
                ),
            });
        }
        last = section;
        let seq = field_int(&l[73..80]);
        let expected = by[section].len() as i64 + 1;
        if seq != Some(expected) {
            return Err(IgesError::Section {
                line,
                reason: format!(
                    "sequence number {:?} in section {}, expected {expected}",
                    String::from_utf8_lossy(&l[73..80]).trim(),
                    ORDER[section] as char
                ),
            });
        }
        by[section].push((l, line));
    }
    let [_, g, d, p, t] = by;
    let Some(&(tl, tline)) = t.first() else {
        return Err(IgesError::Section {
            line: bytes.split(|&b| b == b'\n').count(),
            reason: "no terminate (T) section: the file is truncated".into(),
        });
    };
    for (k, (letter, have)) in [('G', g.len()), ('D', d.len()), ('P', p.len())]
        .into_iter()
        .enumerate()
    {
        let f = &tl[8 * (k + 1)..8 * (k + 2)];
        let said = (f[0] == letter as u8).then(|| field_int(&f[1..])).flatten();
        if said != Some(have as i64) {
            return Err(IgesError::Section {
                line: tline,
                reason: format!(
                    "the terminate section gives {:?} for section {letter}, which has {have} lines",
                    String::from_utf8_lossy(f)
                ),
            });
        }
    }
    if d.len() % 2 != 0 {
        return Err(IgesError::Section {
            line: d.last().map_or(tline, |x| x.1),
            reason: "the directory section has an odd number of lines (entries are pairs)".into(),
        });
    }
    let gtext: Vec<u8> = g
        .iter()
        .flat_map(|(l, _)| l[..72].iter().copied())
        .collect();
    let global = parse_global(&gtext).map_err(|reason| IgesError::Section {
        line: g.first().map_or(tline, |x| x.1),
        reason: format!("global section: {reason}"),
    })?;
    Ok(Sections {
        global,
        directory: d,
        parameter: p,
    })
}

/// An integer in a fixed field (blank = 0), `None` if not an integer.
pub(crate) fn field_int(f: &[u8]) -> Option<i64> {
    let s = std::str::from_utf8(f).ok()?.trim();
    if s.is_empty() {
        return Some(0);
    }
    s.parse().ok()
}

/// The global section: its two delimiters first (each `1Hc`, or empty for the defaults `,` and
/// `;`), then the parameters.
fn parse_global(text: &[u8]) -> Result<Global, String> {
    let mut pos = 0;
    let skip_blanks = |pos: &mut usize| {
        while text.get(*pos) == Some(&b' ') {
            *pos += 1;
        }
    };
    skip_blanks(&mut pos);
    // Parameter delimiter.
    let param_delim = if text[pos..].starts_with(b"1H") {
        let c = *text
            .get(pos + 2)
            .ok_or("ends inside the parameter delimiter")?;
        pos += 3;
        skip_blanks(&mut pos);
        if text.get(pos) != Some(&c) {
            return Err("the parameter delimiter is not followed by itself".into());
        }
        pos += 1;
        c
    } else if text.get(pos) == Some(&b',') {
        pos += 1;
        b','
    } else {
        return Err("it does not start with the parameter delimiter (`1Hc` or `,`)".into());
    };
    skip_blanks(&mut pos);
    let record_delim = if text[pos..].starts_with(b"1H") {
        let c = *text
            .get(pos + 2)
            .ok_or("ends inside the record delimiter")?;
        pos += 3;
        skip_blanks(&mut pos);
        match text.get(pos) {
            Some(&d) if d == param_delim => pos += 1,
            Some(&d) if d == c => {}
            _ => return Err("the record delimiter is not followed by a delimiter".into()),
        }
        c
    } else if text.get(pos) == Some(&param_delim) {
        pos += 1;
        b';'
    } else if text.get(pos) == Some(&b';') {
        b';'
    } else {
        return Err("the record delimiter is neither `1Hc` nor empty".into());
    };
    if param_delim == record_delim || param_delim == b' ' || record_delim == b' ' {
        return Err("the parameter and record delimiters must differ and not be blank".into());
    }
    let mut params = vec![Param::Empty, Param::Str((param_delim as char).into())];
    params.push(Param::Str((record_delim as char).into()));
    let (rest, _) = parse_free(&text[pos..], param_delim, record_delim)?;
    params.extend(rest);
    Ok(Global {
        param_delim,
        record_delim,
        params,
    })
}

/// Free-format parameters up to the record delimiter. Returns them and the byte just after
/// the record delimiter; an error when the text ends first or a token is neither a number nor
/// a Hollerith string.
pub(crate) fn parse_free(text: &[u8], pd: u8, rd: u8) -> Result<(Vec<Param>, usize), String> {
    let mut out = Vec::new();
    let mut pos = 0;
    loop {
        while text.get(pos) == Some(&b' ') {
            pos += 1;
        }
        let start = pos;
        // A Hollerith string: digits, `H`, that many characters.
        let digits = text[pos..]
            .iter()
            .take_while(|b| b.is_ascii_digit())
            .count();
        let param = if digits > 0 && matches!(text.get(pos + digits), Some(b'H' | b'h')) {
            let n: usize = std::str::from_utf8(&text[pos..pos + digits])
                .ok()
                .and_then(|s| s.parse().ok())
                .ok_or("bad Hollerith count")?;
            let from = pos + digits + 1;
            if n > text.len().saturating_sub(from) {
                return Err(format!(
                    "a Hollerith string of {n} characters runs past the end of the record"
                ));
            }
            pos = from + n;
            Param::Str(String::from_utf8_lossy(&text[from..pos]).into_owned())
        } else {
            while let Some(&b) = text.get(pos) {
                if b == pd || b == rd {
                    break;
                }
                pos += 1;
            }
            number(&text[start..pos])?
        };
        while text.get(pos) == Some(&b' ') {
            pos += 1;
        }
        match text.get(pos) {
            Some(&b) if b == pd => {
                out.push(param);
                pos += 1;
            }
            Some(&b) if b == rd => {
                out.push(param);
                return Ok((out, pos + 1));
            }
            Some(&b) => {
                return Err(format!(
                    "{:?} after parameter {} where a delimiter belongs",
                    b as char,
                    out.len() + 1
                ));
            }
            None => {
                return Err(format!(
                    "the record ends after {} parameters without its record delimiter",
                    out.len()
                ));
            }
        }
    }
}

/// A numeric token (blanks ignored; `D` exponents allowed), or `Empty`.
fn number(token: &[u8]) -> Result<Param, String> {
    let s: String = token
        .iter()
        .filter(|b| **b != b' ')
        .map(|&b| match b {
            b'D' | b'd' => 'E',
            b => b as char,
        })
        .collect();
    if s.is_empty() {
        return Ok(Param::Empty);
    }
    if let Ok(i) = s.parse::<i64>() {
        return Ok(Param::Int(i));
    }
    match s.parse::<f64>() {
        Ok(r) if r.is_finite() => Ok(Param::Real(r)),
        _ => Err(format!("{s:?} is not a number")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hollerith_strings_may_hold_delimiters() {
        let (p, end) = parse_free(b"3H,;a,1.5D2, ,-7;x", b',', b';').expect("parses");
        assert_eq!(
            p,
            vec![
                Param::Str(",;a".into()),
                Param::Real(150.0),
                Param::Empty,
                Param::Int(-7)
            ]
        );
        assert_eq!(end, 17);
    }

    #[test]
    fn other_delimiters_and_defaults() {
        let g = parse_global(b"1H//1H#/2Hab//1.#").expect("parses");
        assert_eq!((g.param_delim, g.record_delim), (b'/', b'#'));
        assert_eq!(g.get(3), &Param::Str("ab".into()));
        assert_eq!(g.get(4), &Param::Empty);
        assert_eq!(g.get(5), &Param::Real(1.0));
        let g = parse_global(b",,2HAB;").expect("parses");
        assert_eq!((g.param_delim, g.record_delim), (b',', b';'));
        assert_eq!(g.get(3), &Param::Str("AB".into()));
    }

    #[test]
    fn hostile_records_are_errors() {
        assert!(parse_free(b"99Habc;", b',', b';').is_err());
        assert!(parse_free(b"1,2", b',', b';').is_err());
        assert!(parse_free(b"1x,2;", b',', b';').is_err());
        assert!(parse_global(b"1H,").is_err());
    }
}
