//! The lexical level of the Part 21 scanner (ISO 10303-21:2016): whitespace and
//! comments (counting lines), keywords, numbers, enumerations, binaries, and strings with
//! their `''` escapes and control directives (`\X\`, `\X2\`, `\X4\`, `\S\`, `\P`), plus the
//! descriptions of the token at hand that errors carry. The grammar is in `parser`.

use super::{P21Error, Param, Parser, Res};

pub(super) fn is_keyword_start(c: u8) -> bool {
    c.is_ascii_alphabetic() || c == b'!' || c == b'_'
}

fn is_keyword_char(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_'
}

impl<'a> Parser<'a> {
    /// Reads `[A-Za-z0-9_-]*` at `pos` (section keywords contain dashes).
    pub(super) fn section_word(&mut self) -> &'a str {
        let start = self.pos;
        while self
            .b
            .get(self.pos)
            .is_some_and(|&c| is_keyword_char(c) || c == b'-')
        {
            self.pos += 1;
        }
        self.text.get(start..self.pos).unwrap_or("")
    }

    pub(super) fn eat_keyword_with_dashes(&mut self, word: &str) -> bool {
        let start = self.pos;
        if self.section_word() == word {
            true
        } else {
            self.pos = start;
            false
        }
    }

    /// Reads a keyword at `pos` (which is a keyword start) and returns it in upper case.
    pub(super) fn keyword(&mut self) -> String {
        let start = self.pos;
        self.pos += 1;
        while self.b.get(self.pos).is_some_and(|&c| is_keyword_char(c)) {
            self.pos += 1;
        }
        let word = self.text.get(start..self.pos).unwrap_or("");
        if word.bytes().any(|c| c.is_ascii_lowercase()) {
            word.to_ascii_uppercase()
        } else {
            word.to_owned()
        }
    }

    /// Decimal digits at `pos` as an entity number.
    pub(super) fn digits_as_u64(&mut self, expected: &'static str) -> Res<u64> {
        let start = self.pos;
        while self.b.get(self.pos).is_some_and(u8::is_ascii_digit) {
            self.pos += 1;
        }
        if start == self.pos {
            return Err(self.unexpected(expected));
        }
        let digits = self.text.get(start..self.pos).unwrap_or("");
        digits.parse().map_err(|_| P21Error::BadNumber {
            line: self.line,
            entity: self.entity,
            text: digits.to_owned(),
        })
    }

    /// `[+-]digits[.digits][E[+-]digits]`.
    pub(super) fn number(&mut self) -> Res<Param> {
        let start = self.pos;
        let digit = |p: &Self| p.b.get(p.pos).is_some_and(u8::is_ascii_digit);
        if matches!(self.b.get(self.pos), Some(b'+' | b'-')) {
            self.pos += 1;
        }
        let mut ok = digit(self);
        while digit(self) {
            self.pos += 1;
        }
        let mut real = false;
        if self.b.get(self.pos) == Some(&b'.') {
            real = true;
            self.pos += 1;
            while digit(self) {
                self.pos += 1;
            }
        }
        if matches!(self.b.get(self.pos), Some(b'e' | b'E')) {
            real = true;
            self.pos += 1;
            if matches!(self.b.get(self.pos), Some(b'+' | b'-')) {
                self.pos += 1;
            }
            ok &= digit(self);
            while digit(self) {
                self.pos += 1;
            }
        }
        // Glued garbage such as `1.2.3` or `12abc` belongs to the bad number.
        while self
            .b
            .get(self.pos)
            .is_some_and(|&c| is_keyword_char(c) || c == b'.')
        {
            ok = false;
            self.pos += 1;
        }
        let text = self.text.get(start..self.pos).unwrap_or("");
        let bad = || P21Error::BadNumber {
            line: self.line,
            entity: self.entity,
            text: text.to_owned(),
        };
        if !ok {
            return Err(bad());
        }
        if !real && let Ok(i) = text.parse::<i64>() {
            return Ok(Param::Int(i));
        }
        match text.parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(Param::Real(x)),
            _ => Err(bad()),
        }
    }

    /// `.NAME.`, with `pos` at the first dot.
    pub(super) fn enumeration(&mut self) -> Res<Param> {
        let start = self.pos;
        self.pos += 1;
        if self.b.get(self.pos).is_some_and(u8::is_ascii_digit) {
            while self
                .b
                .get(self.pos)
                .is_some_and(|&c| is_keyword_char(c) || c == b'.')
            {
                self.pos += 1;
            }
            return Err(P21Error::BadNumber {
                line: self.line,
                entity: self.entity,
                text: self.text.get(start..self.pos).unwrap_or("").to_owned(),
            });
        }
        let name_start = self.pos;
        while self.b.get(self.pos).is_some_and(|&c| is_keyword_char(c)) {
            self.pos += 1;
        }
        let name_end = self.pos;
        if name_start == name_end || self.b.get(self.pos) != Some(&b'.') {
            return Err(self.unexpected("an enumeration such as .T."));
        }
        self.pos += 1;
        let name = self.text.get(name_start..name_end).unwrap_or("");
        Ok(Param::Enum(name.to_ascii_uppercase()))
    }

    /// `"hex"`, with `pos` at the opening quote.
    pub(super) fn binary(&mut self) -> Res<Param> {
        let line = self.line;
        self.pos += 1;
        let start = self.pos;
        while self.b.get(self.pos).is_some_and(u8::is_ascii_hexdigit) {
            self.pos += 1;
        }
        match self.b.get(self.pos) {
            Some(b'"') => {
                let hex = self.text.get(start..self.pos).unwrap_or("").to_owned();
                self.pos += 1;
                Ok(Param::Binary(hex))
            }
            None => Err(P21Error::UnterminatedString {
                line,
                entity: self.entity,
            }),
            Some(_) => Err(self.unexpected("a hexadecimal digit or '\"' in a binary")),
        }
    }

    /// A string, with `pos` at the opening quote; returns it decoded.
    pub(super) fn string(&mut self) -> Res<String> {
        let line = self.line;
        self.pos += 1;
        let start = self.pos;
        let mut plain = true;
        loop {
            match self.b.get(self.pos) {
                None => {
                    return Err(P21Error::UnterminatedString {
                        line,
                        entity: self.entity,
                    });
                }
                Some(b'\'') => {
                    if self.b.get(self.pos + 1) == Some(&b'\'') {
                        plain = false;
                        self.pos += 2;
                    } else {
                        break;
                    }
                }
                Some(b'\n') => {
                    plain = false;
                    self.line += 1;
                    self.pos += 1;
                }
                Some(b'\r' | b'\\') => {
                    plain = false;
                    self.pos += 1;
                }
                Some(_) => self.pos += 1,
            }
        }
        let raw = self.text.get(start..self.pos).unwrap_or("");
        self.pos += 1;
        Ok(if plain {
            raw.to_owned()
        } else {
            decode_string(raw)
        })
    }

    /// Skips whitespace and comments, counting lines.
    pub(super) fn skip_ws(&mut self) -> Res<()> {
        loop {
            match self.b.get(self.pos) {
                Some(b'\n') => {
                    self.line += 1;
                    self.pos += 1;
                }
                Some(b' ' | b'\t' | b'\r' | b'\x0b' | b'\x0c') => self.pos += 1,
                Some(b'/') if self.b.get(self.pos + 1) == Some(&b'*') => {
                    let line = self.line;
                    self.pos += 2;
                    loop {
                        match self.b.get(self.pos) {
                            None => {
                                return Err(P21Error::UnterminatedComment {
                                    line,
                                    entity: self.entity,
                                });
                            }
                            Some(b'*') if self.b.get(self.pos + 1) == Some(&b'/') => {
                                self.pos += 2;
                                break;
                            }
                            Some(b'\n') => {
                                self.line += 1;
                                self.pos += 1;
                            }
                            Some(_) => self.pos += 1,
                        }
                    }
                }
                _ => return Ok(()),
            }
        }
    }

    /// Describes the token at `pos` for an error message.
    pub(super) fn found(&self) -> String {
        let rest = self.text.get(self.pos..).unwrap_or("");
        let Some(first) = rest.chars().next() else {
            return "end of file".to_owned();
        };
        let run: String = rest
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '.' | '-' | '+' | '#'))
            .take(24)
            .collect();
        if run.chars().count() > 1 {
            format!("'{run}'")
        } else {
            format!("'{first}'")
        }
    }

    pub(super) fn unexpected(&self, expected: &'static str) -> P21Error {
        if self.pos >= self.b.len() {
            return self.eof(expected);
        }
        P21Error::Unexpected {
            line: self.line,
            entity: self.entity,
            expected,
            found: self.found(),
        }
    }

    pub(super) fn eof(&self, expected: &'static str) -> P21Error {
        P21Error::UnexpectedEof {
            line: self.line,
            entity: self.entity,
            expected,
        }
    }
}

/// Decodes the body of a string that contains `''`, `\` or line breaks.
fn decode_string(raw: &str) -> String {
    let mut out = String::with_capacity(raw.len());
    let mut rest = raw;
    while let Some(c) = rest.chars().next() {
        match c {
            '\'' => {
                out.push('\'');
                rest = rest.strip_prefix("''").unwrap_or(&rest[1..]);
            }
            '\r' | '\n' => rest = &rest[1..],
            '\\' => {
                let (decoded, used) = decode_directive(rest);
                match decoded {
                    Some(d) => {
                        out.push_str(&d);
                        rest = rest.get(used..).unwrap_or("");
                    }
                    None => {
                        out.push('\\');
                        rest = &rest[1..];
                    }
                }
            }
            c => {
                out.push(c);
                rest = &rest[c.len_utf8()..];
            }
        }
    }
    out
}

/// Decodes a control directive at the start of `s` (which starts with `\`): the text it stands
/// for and the bytes it uses, or `None` if it is malformed.
fn decode_directive(s: &str) -> (Option<String>, usize) {
    let hex = |t: &str| u32::from_str_radix(t, 16).ok();
    if s.starts_with("\\\\") {
        return (Some("\\".to_owned()), 2);
    }
    if let Some(body) = s
        .strip_prefix("\\X2\\")
        .or_else(|| s.strip_prefix("\\X4\\"))
    {
        let width = if s.starts_with("\\X2\\") { 4 } else { 8 };
        let Some(end) = body.find("\\X0\\") else {
            return (None, 0);
        };
        let digits = &body[..end];
        if digits.len() % width != 0 || !digits.bytes().all(|c| c.is_ascii_hexdigit()) {
            return (None, 0);
        }
        let units: Vec<u32> = (0..digits.len() / width)
            .filter_map(|i| digits.get(i * width..(i + 1) * width).and_then(hex))
            .collect();
        let text: String = if width == 4 {
            let u16s: Vec<u16> = units.iter().map(|&u| u as u16).collect();
            char::decode_utf16(u16s)
                .map(|r| r.unwrap_or(char::REPLACEMENT_CHARACTER))
                .collect()
        } else {
            units
                .iter()
                .map(|&u| char::from_u32(u).unwrap_or(char::REPLACEMENT_CHARACTER))
                .collect()
        };
        return (Some(text), 4 + end + 4);
    }
    if let Some(body) = s.strip_prefix("\\X\\") {
        if let Some(code) = body
            .get(..2)
            .filter(|h| h.bytes().all(|c| c.is_ascii_hexdigit()))
            && let Some(code) = hex(code).and_then(char::from_u32)
        {
            return (Some(code.to_string()), 5);
        }
        return (None, 0);
    }
    if let Some(body) = s.strip_prefix("\\S\\") {
        if let Some(c) = body.chars().next().filter(char::is_ascii)
            && let Some(code) = char::from_u32(c as u32 + 128)
        {
            return (Some(code.to_string()), 4);
        }
        return (None, 0);
    }
    if let Some(body) = s.strip_prefix("\\P")
        && body.chars().next().is_some_and(|c| c.is_ascii_uppercase())
        && body.get(1..2) == Some("\\")
    {
        return (Some(String::new()), 4);
    }
    (None, 0)
}

#[cfg(test)]
mod tests {
    use super::super::fixtures::{err, wrap};
    use super::super::parse;
    use super::*;

    #[test]
    fn every_parameter_kind() {
        let text = wrap(
            "/* c */ #1 = ( A ( 1 , -2 , +3 ) b_c ( 1.E-05 , -2.5E+3 , 0. , 7.25e2 ) );\n\
             #2=X('it''s',.T.,.unspecified.,$,*,#1,(),((#1,$),'a'),\"0F\",\
             LENGTH_MEASURE(2.5),T2(1,2),'\\X2\\00E9\\X0\\t\\\\e\\S\\a',99999999999999999999);",
        );
        let file = parse(&text).expect("parses");
        let a = file.get(1).expect("#1");
        assert_eq!(a.parts.len(), 2);
        assert_eq!(
            a.parts[0].args,
            [Param::Int(1), Param::Int(-2), Param::Int(3)]
        );
        assert_eq!(a.parts[1].name, "B_C");
        assert_eq!(
            a.parts[1].args,
            [
                Param::Real(1e-5),
                Param::Real(-2500.0),
                Param::Real(0.0),
                Param::Real(725.0)
            ]
        );
        let x = file.get(2).expect("#2").record().expect("record");
        use Param::*;
        assert_eq!(
            x.args,
            [
                Str("it's".into()),
                Enum("T".into()),
                Enum("UNSPECIFIED".into()),
                Unset,
                Derived,
                Ref(1),
                List(vec![]),
                List(vec![List(vec![Ref(1), Unset]), Str("a".into())]),
                Binary("0F".into()),
                Typed("LENGTH_MEASURE".into(), Box::new(Real(2.5))),
                Typed("T2".into(), Box::new(List(vec![Int(1), Int(2)]))),
                Str("ét\\e\u{e1}".into()),
                Real(99999999999999999999.0),
            ]
        );
        assert_eq!(file.get(2).map(|e| e.line), Some(7));
    }

    #[test]
    fn error_unterminated_string() {
        let e = err("#1=A('ok');\n#2=B('never\nclosed);");
        assert_eq!(
            e,
            P21Error::UnterminatedString {
                line: 7,
                entity: Some(2)
            }
        );
        assert_eq!(e.to_string(), "line 7, entity #2: unterminated string");
    }

    #[test]
    fn error_unterminated_comment() {
        let e = err("#1=A();\n/* no end\n#2=B();");
        assert_eq!(
            e,
            P21Error::UnterminatedComment {
                line: 7,
                entity: None
            }
        );
    }

    #[test]
    fn error_bad_number() {
        for (data, text) in [
            ("#1=A(1.2.3);", "1.2.3"),
            ("#1=A(-);", "-"),
            ("#1=A(1E);", "1E"),
            ("#1=A(1E999);", "1E999"),
            ("#1=A(12abc);", "12abc"),
            ("#1=A(.5);", ".5"),
            ("#99999999999999999999999=A();", "99999999999999999999999"),
        ] {
            let e = err(data);
            assert!(
                matches!(&e, P21Error::BadNumber { line: 6, text: t, .. } if t == text),
                "{e}"
            );
        }
    }
}
