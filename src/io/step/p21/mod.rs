//! ISO 10303-21 ("STEP physical file", "Part 21") scanner: text → entity instances.
//!
//! Implements the exchange-structure syntax of ISO 10303-21:2016 (edition 3), clauses 5–12:
//! `ISO-10303-21;`, the `HEADER` section, one or more `DATA` sections (an optional parameter
//! list after `DATA` is read and ignored), `ENDSEC;`, `END-ISO-10303-21;`; comments
//! `/* … */` wherever whitespace may stand; simple records `#12 = NAME(args);` and complex
//! records `#12 = ( A(args) B(args) C() );`; parameters: strings with `''` escapes, enumerations
//! `.T.`, entity references `#123`, `$`, `*`, integers, reals (`1.E-05`, `-2.5E+3`, `0.`),
//! binaries `"0F3"`, nested lists and typed parameters such as `LENGTH_MEASURE(2.5)`.
//!
//! This module holds the API: the parsed file, its records and parameters, and [`P21Error`];
//! `lexer` reads the tokens and `parser` the exchange structure.
//!
//! # Guarantees
//!
//! - [`parse`] never panics: on any input it returns a [`P21File`] or a [`P21Error`] that names
//!   the 1-based line and, inside an entity instance, its `#id`. List nesting is capped at
//!   `MAX_NESTING` so that hostile input cannot overflow the stack.
//! - Entities are kept in file order; [`P21File::get`] finds one by id in O(1). Duplicate ids
//!   are an error.
//! - Record names are upper case. Strings are decoded: `''` → `'`, `\\` → `\`, the `\X\hh`,
//!   `\X2\…\X0\`, `\X4\…\X0\` and `\S\c` control directives become the characters they encode,
//!   `\Px\` code-page directives are dropped, and line breaks inside a string are removed (line
//!   ends carry no meaning in a Part 21 file). A malformed directive is kept as written.
//! - Real numbers must be finite (`1E999` is a [`P21Error::BadNumber`]); an integer too large
//!   for `i64` is read as a real.
//!
//! # Not done
//!
//! No schema is checked: the scanner does not know which entities exist or how many attributes
//! they take. Edition 3 `ANCHOR`, `REFERENCE` and `SIGNATURE` sections are skipped; value
//! instance names (`@12`) are not read. Anything after `END-ISO-10303-21;` is ignored, and a
//! file that ends right after the `ENDSEC;` of a `DATA` section is accepted.

mod lexer;
mod parser;

use std::collections::HashMap;
use std::fmt;

/// Deepest nesting of lists and typed parameters accepted inside one record.
pub(crate) const MAX_NESTING: usize = 128;

/// A parsed STEP physical file.
#[derive(Debug, Clone, Default)]
pub struct P21File {
    /// Schema names from `FILE_SCHEMA`, e.g. `AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }`.
    pub schemas: Vec<String>,
    /// The `name` attribute of `FILE_NAME`, if the header has one.
    pub file_name: Option<String>,
    /// Every header record (`FILE_DESCRIPTION`, `FILE_NAME`, `FILE_SCHEMA`, …) in file order.
    pub header: Vec<Record>,
    /// Entity instances of all `DATA` sections, in file order.
    pub entities: Vec<Entity>,
    /// Byte offset in the text just after the last statement read (`END-ISO-10303-21;`, or
    /// the end of the text): what follows was not read, and must not reach another parser.
    pub end: usize,
    /// Entity id → index into `entities`.
    index: HashMap<u64, usize>,
}

impl P21File {
    /// The entity instance `#id`, if the file has one.
    pub fn get(&self, id: u64) -> Option<&Entity> {
        self.index.get(&id).and_then(|&i| self.entities.get(i))
    }

    /// Number of entity instances.
    pub fn len(&self) -> usize {
        self.entities.len()
    }

    /// Whether the file has no entity instances.
    pub fn is_empty(&self) -> bool {
        self.entities.is_empty()
    }
}

/// One entity instance `#id = …;`.
#[derive(Debug, Clone, PartialEq)]
pub struct Entity {
    /// The instance name, `#id`.
    pub id: u64,
    /// 1-based line where `#id` starts.
    pub line: usize,
    /// One record for a simple instance; the partial records, in file order, for a complex one.
    pub parts: Vec<Record>,
}

impl Entity {
    /// Whether any record of the instance is called `name` (upper case).
    pub fn has(&self, name: &str) -> bool {
        self.parts.iter().any(|r| r.name == name)
    }

    /// The record called `name` (upper case), if any.
    pub fn part(&self, name: &str) -> Option<&Record> {
        self.parts.iter().find(|r| r.name == name)
    }

    /// Whether the instance was written as a complex record `( A() B() )`.
    pub(crate) fn is_complex(&self) -> bool {
        self.parts.len() > 1
    }

    /// The record of a simple instance (the first record of a complex one).
    pub fn record(&self) -> Option<&Record> {
        self.parts.first()
    }

    /// Type name: the record name, or for a complex instance the names joined by `+`
    /// (`LENGTH_UNIT+NAMED_UNIT+SI_UNIT`).
    pub(crate) fn type_name(&self) -> String {
        let names: Vec<&str> = self.parts.iter().map(|r| r.name.as_str()).collect();
        names.join("+")
    }
}

/// A record `NAME(args)`: a simple entity instance, a part of a complex one, or a header entry.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// Entity name in upper case.
    pub name: String,
    /// Attribute values in order.
    pub args: Vec<Param>,
}

impl Record {
    /// Attribute `i`, if present.
    pub fn arg(&self, i: usize) -> Option<&Param> {
        self.args.get(i)
    }

    /// Attribute `i` as an entity reference.
    pub fn ref_at(&self, i: usize) -> Option<u64> {
        self.arg(i).and_then(Param::as_ref)
    }

    /// Attribute `i` as a number (see [`Param::as_f64`]).
    pub(crate) fn f64_at(&self, i: usize) -> Option<f64> {
        self.arg(i).and_then(Param::as_f64)
    }

    /// Attribute `i` as a string.
    pub(crate) fn str_at(&self, i: usize) -> Option<&str> {
        self.arg(i).and_then(Param::as_str)
    }

    /// Attribute `i` as a list.
    pub fn list_at(&self, i: usize) -> Option<&[Param]> {
        self.arg(i).and_then(Param::as_list)
    }
}

/// A parameter value.
#[derive(Debug, Clone, PartialEq)]
pub enum Param {
    /// Entity reference `#123`.
    Ref(u64),
    /// Integer `42`, `-7`.
    Int(i64),
    /// Real `1.E-05`, `0.`; always finite.
    Real(f64),
    /// String, decoded (see the module documentation).
    Str(String),
    /// Enumeration or logical without the dots: `.T.` → `T`, `.UNSPECIFIED.` → `UNSPECIFIED`.
    Enum(String),
    /// Binary `"0F3"`, the hexadecimal text as written (first digit = unused bit count).
    Binary(String),
    /// List `( … )`.
    List(Vec<Param>),
    /// Typed parameter `LENGTH_MEASURE(2.5)`. A typed parameter with other than exactly one
    /// value (not valid Part 21, but written by some exporters) holds them as a [`Param::List`].
    Typed(String, Box<Param>),
    /// `$`: no value.
    Unset,
    /// `*`: value derived from a supertype attribute.
    Derived,
}

impl Param {
    /// The referenced entity id of a [`Param::Ref`].
    pub fn as_ref(&self) -> Option<u64> {
        match self {
            Param::Ref(id) => Some(*id),
            _ => None,
        }
    }

    /// The value of an [`Param::Int`] or [`Param::Real`], looking through typed parameters
    /// (`LENGTH_MEASURE(2.5)` → 2.5).
    pub fn as_f64(&self) -> Option<f64> {
        match self {
            Param::Int(i) => Some(*i as f64),
            Param::Real(x) => Some(*x),
            Param::Typed(_, inner) => inner.as_f64(),
            _ => None,
        }
    }

    /// The items of a [`Param::List`].
    pub(crate) fn as_list(&self) -> Option<&[Param]> {
        match self {
            Param::List(items) => Some(items),
            _ => None,
        }
    }

    /// The text of a [`Param::Str`], looking through typed parameters (`LABEL('x')` → `x`).
    pub fn as_str(&self) -> Option<&str> {
        match self {
            Param::Str(s) => Some(s),
            Param::Typed(_, inner) => inner.as_str(),
            _ => None,
        }
    }

    /// The name of a [`Param::Enum`] without dots.
    pub(crate) fn as_enum(&self) -> Option<&str> {
        match self {
            Param::Enum(s) => Some(s),
            _ => None,
        }
    }
}

/// Why a text could not be read as a STEP physical file. Lines are 1-based; `entity` is the
/// `#id` of the instance being read, when the error is inside one. The caller adds the path.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum P21Error {
    /// The text does not start with `ISO-10303-21;` (leading whitespace, comments and a BOM
    /// are allowed).
    #[error("line {line}: not a STEP file: it does not start with `ISO-10303-21;`")]
    NotStep { line: usize },

    /// The file has no `DATA` section.
    #[error("line {line}: no DATA section")]
    NoData { line: usize },

    /// The text ends in the middle of a section, record or parameter (`line` = last line).
    #[error("line {line}{}: unexpected end of file, expected {expected}", At(.entity))]
    UnexpectedEof {
        line: usize,
        entity: Option<u64>,
        expected: &'static str,
    },

    /// A string `'…` without its closing quote (`line` = where it starts).
    #[error("line {line}{}: unterminated string", At(.entity))]
    UnterminatedString { line: usize, entity: Option<u64> },

    /// A comment `/*…` without `*/` (`line` = where it starts).
    #[error("line {line}{}: unterminated comment", At(.entity))]
    UnterminatedComment { line: usize, entity: Option<u64> },

    /// A list or argument list that is not closed: something other than `,` or `)` follows a
    /// parameter, or a `;` comes where a parameter should.
    #[error("line {line}{}: expected ')' or ',' in argument list, found {found}", At(.entity))]
    UnterminatedList {
        line: usize,
        entity: Option<u64>,
        found: String,
    },

    /// A record is not followed by `;` (`line` = where the record ends).
    #[error("line {line}{}: expected ';' after the record, found {found}", At(.entity))]
    MissingSemicolon {
        line: usize,
        entity: Option<u64>,
        found: String,
    },

    /// `#id` is not followed by `=`.
    #[error("line {line}{}: expected '=' after the entity number, found {found}", At(.entity))]
    MissingEquals {
        line: usize,
        entity: Option<u64>,
        found: String,
    },

    /// A malformed or out-of-range number (also an entity number too large for `u64`).
    #[error("line {line}{}: bad number {text:?}", At(.entity))]
    BadNumber {
        line: usize,
        entity: Option<u64>,
        text: String,
    },

    /// Two instances with the same `#id`.
    #[error(
        "line {line}, entity #{entity}: duplicate entity id, first defined on line {first_line}"
    )]
    DuplicateId {
        line: usize,
        entity: u64,
        first_line: usize,
    },

    /// Lists nested deeper than `MAX_NESTING`.
    #[error("line {line}{}: lists nested deeper than {MAX_NESTING}", At(.entity))]
    TooDeep { line: usize, entity: Option<u64> },

    /// Any other token out of place.
    #[error("line {line}{}: expected {expected}, found {found}", At(.entity))]
    Unexpected {
        line: usize,
        entity: Option<u64>,
        expected: &'static str,
        found: String,
    },
}

impl P21Error {
    /// The 1-based line the error points at.
    pub fn line(&self) -> usize {
        match self {
            P21Error::NotStep { line }
            | P21Error::NoData { line }
            | P21Error::UnexpectedEof { line, .. }
            | P21Error::UnterminatedString { line, .. }
            | P21Error::UnterminatedComment { line, .. }
            | P21Error::UnterminatedList { line, .. }
            | P21Error::MissingSemicolon { line, .. }
            | P21Error::MissingEquals { line, .. }
            | P21Error::BadNumber { line, .. }
            | P21Error::DuplicateId { line, .. }
            | P21Error::TooDeep { line, .. }
            | P21Error::Unexpected { line, .. } => *line,
        }
    }

    /// The message without its leading `line N`, for callers that print the line themselves
    /// (`x.stp:812: entity #455: expected …`).
    pub fn reason(&self) -> String {
        let text = self.to_string();
        let prefix = format!("line {}", self.line());
        let rest = text.strip_prefix(&prefix).unwrap_or(&text);
        rest.strip_prefix(": ")
            .or_else(|| rest.strip_prefix(", "))
            .unwrap_or(rest)
            .to_owned()
    }

    /// The `#id` of the entity instance the error is in, if it is in one.
    pub fn entity(&self) -> Option<u64> {
        match self {
            P21Error::NotStep { .. } | P21Error::NoData { .. } => None,
            P21Error::DuplicateId { entity, .. } => Some(*entity),
            P21Error::UnexpectedEof { entity, .. }
            | P21Error::UnterminatedString { entity, .. }
            | P21Error::UnterminatedComment { entity, .. }
            | P21Error::UnterminatedList { entity, .. }
            | P21Error::MissingSemicolon { entity, .. }
            | P21Error::MissingEquals { entity, .. }
            | P21Error::BadNumber { entity, .. }
            | P21Error::TooDeep { entity, .. }
            | P21Error::Unexpected { entity, .. } => *entity,
        }
    }
}

/// Displays `, entity #id` or nothing.
struct At<'a>(&'a Option<u64>);

impl fmt::Display for At<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Some(id) => write!(f, ", entity #{id}"),
            None => Ok(()),
        }
    }
}

/// Parses the text of a STEP physical file.
pub fn parse(text: &str) -> Result<P21File, P21Error> {
    let mut p = Parser {
        text,
        b: text.as_bytes(),
        pos: 0,
        line: 1,
        entity: None,
        depth: 0,
    };
    p.file()
}

/// Parses a file's bytes. Part 21 files are ASCII, but some exporters put Latin-1 or other
/// 8-bit text in strings; bytes that are not UTF-8 become U+FFFD instead of failing the whole
/// file (valid UTF-8 is not copied).
pub fn parse_bytes(bytes: &[u8]) -> Result<P21File, P21Error> {
    parse(&String::from_utf8_lossy(bytes))
}

/// Recursive-descent parser over the bytes of the text. Every token boundary it slices at is an
/// ASCII byte, so slices of `text` are always on character boundaries; `get` is used anyway.
struct Parser<'a> {
    text: &'a str,
    b: &'a [u8],
    pos: usize,
    /// Line of `pos`, kept up to date by everything that can step over a line feed
    /// (whitespace, comments, strings).
    line: usize,
    /// Id of the instance being read, for errors.
    entity: Option<u64>,
    /// Current list nesting.
    depth: usize,
}

type Res<T> = Result<T, P21Error>;

/// Files and helpers shared by the tests of the scanner's modules.
#[cfg(test)]
pub(crate) mod fixtures {
    use super::{P21Error, parse};

    const MODELS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/models/");
    pub(super) const FILES: [&str; 5] = [
        "as1-oc-214.stp",
        "NIST_MBE_PMI_3.stp",
        "NIST_MBE_PMI_11.stp",
        "nist_ctc_01_asme1_rd.stp",
        "screw.step",
    ];

    pub(super) fn model(name: &str) -> String {
        std::fs::read_to_string(format!("{MODELS}{name}")).expect("model file is readable")
    }

    /// `data` (entity instances) as a whole exchange structure.
    pub(crate) fn wrap(data: &str) -> String {
        format!(
            "ISO-10303-21;\nHEADER;\nFILE_SCHEMA(('TEST'));\nENDSEC;\nDATA;\n{data}\nENDSEC;\n\
             END-ISO-10303-21;\n"
        )
    }

    pub(super) fn err(data: &str) -> P21Error {
        parse(&wrap(data)).expect_err("the text is malformed")
    }
}

#[cfg(test)]
mod tests {
    use super::fixtures::{FILES, model, wrap};
    use super::*;

    #[test]
    fn all_models_parse_with_every_entity_indexed() {
        for name in FILES {
            let text = model(name);
            let file = parse(&text).unwrap_or_else(|e| panic!("{name}: {e}"));
            let instances = text.matches('#').count();
            assert!(file.len() > 100, "{name}: {} entities", file.len());
            assert!(file.len() <= instances);
            for (i, e) in file.entities.iter().enumerate() {
                assert_eq!(file.get(e.id).map(|x| x.id), Some(e.id));
                assert!(i == 0 || file.entities[i - 1].line <= e.line);
            }
            assert!(!file.schemas.is_empty(), "{name}");
        }
    }

    #[test]
    fn bytes_that_are_not_utf8_only_spoil_their_string() {
        let text = wrap("#1=A('caf\u{e9}');").replace('\u{e9}', "\u{1}");
        let mut bytes = text.into_bytes();
        let i = bytes.iter().position(|&c| c == 1).expect("marker");
        bytes[i] = 0xe9; // Latin-1 é
        let file = parse_bytes(&bytes).expect("parses");
        let r = file.get(1).and_then(Entity::record).expect("record");
        assert_eq!(r.str_at(0), Some("caf\u{fffd}"));
    }

    #[test]
    fn error_no_data_section() {
        let e = parse("ISO-10303-21;\nHEADER;\nENDSEC;\nEND-ISO-10303-21;\n").expect_err("no data");
        assert_eq!(e, P21Error::NoData { line: 4 });
        assert_eq!(e.to_string(), "line 4: no DATA section");
        assert_eq!(e.reason(), "no DATA section");
    }

    /// A small xorshift generator, so the fuzz cases are the same on every run.
    struct Rng(u64);

    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            self.0
        }
        fn below(&mut self, n: usize) -> usize {
            (self.next() % n.max(1) as u64) as usize
        }
    }

    #[test]
    fn never_panics_on_truncations_mutations_and_noise() {
        let text = model("screw.step");
        // Every truncation of the first 6000 bytes, then a sparse sample of the rest.
        let boundaries: Vec<usize> = (0..=text.len())
            .filter(|&i| text.is_char_boundary(i))
            .collect();
        for (k, &cut) in boundaries.iter().enumerate() {
            if cut < 6000 || k % 97 == 0 {
                let _ = parse(&text[..cut]);
            }
        }
        // Byte mutations from an alphabet of syntax characters.
        let alphabet = b"#=();,'\"$*.-+0123456789EeAZ_/ \n\\";
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        for _ in 0..2000 {
            let mut bytes = text.as_bytes()[..text.len().min(8000)].to_vec();
            for _ in 0..1 + rng.below(8) {
                let i = rng.below(bytes.len());
                bytes[i] = alphabet[rng.below(alphabet.len())];
            }
            if let Ok(s) = std::str::from_utf8(&bytes) {
                let _ = parse(s);
            }
        }
        // Pure noise, with and without a valid start.
        for _ in 0..3000 {
            let len = rng.below(300);
            let noise: String = (0..len)
                .map(|_| {
                    if rng.below(10) == 0 {
                        char::from_u32(rng.below(0x3000) as u32).unwrap_or('x')
                    } else {
                        alphabet[rng.below(alphabet.len())] as char
                    }
                })
                .collect();
            let _ = parse(&noise);
            let _ = parse(&format!("ISO-10303-21;HEADER;ENDSEC;DATA;{noise}"));
            let _ = parse(&format!("ISO-10303-21;HEADER;ENDSEC;DATA;#1=A({noise}"));
        }
    }

    #[test]
    fn parse_time_of_the_largest_model() {
        let text = model("as1-oc-214.stp");
        let start = std::time::Instant::now();
        let file = parse(&text).expect("parses");
        let elapsed = start.elapsed();
        eprintln!("as1-oc-214.stp: {} entities in {elapsed:?}", file.len());
        assert_eq!(file.len(), 6425);
    }
}
