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
//! # Guarantees
//!
//! - [`parse`] never panics: on any input it returns a [`P21File`] or a [`P21Error`] that names
//!   the 1-based line and, inside an entity instance, its `#id`. List nesting is capped at
//!   [`MAX_NESTING`] so that hostile input cannot overflow the stack.
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

use std::collections::HashMap;
use std::fmt;

/// Deepest nesting of lists and typed parameters accepted inside one record.
pub const MAX_NESTING: usize = 128;

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
    pub fn is_complex(&self) -> bool {
        self.parts.len() > 1
    }

    /// The record of a simple instance (the first record of a complex one).
    pub fn record(&self) -> Option<&Record> {
        self.parts.first()
    }

    /// Type name: the record name, or for a complex instance the names joined by `+`
    /// (`LENGTH_UNIT+NAMED_UNIT+SI_UNIT`).
    pub fn type_name(&self) -> String {
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
    pub fn f64_at(&self, i: usize) -> Option<f64> {
        self.arg(i).and_then(Param::as_f64)
    }

    /// Attribute `i` as a string.
    pub fn str_at(&self, i: usize) -> Option<&str> {
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
    pub fn as_list(&self) -> Option<&[Param]> {
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
    pub fn as_enum(&self) -> Option<&str> {
        match self {
            Param::Enum(s) => Some(s),
            _ => None,
        }
    }

    /// Whether the value is `$`.
    pub fn is_unset(&self) -> bool {
        matches!(self, Param::Unset)
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

    /// Lists nested deeper than [`MAX_NESTING`].
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

fn is_keyword_start(c: u8) -> bool {
    c.is_ascii_alphabetic() || c == b'!' || c == b'_'
}

fn is_keyword_char(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_'
}

impl<'a> Parser<'a> {
    fn file(&mut self) -> Res<P21File> {
        if self.b.starts_with("\u{feff}".as_bytes()) {
            self.pos = 3;
        }
        self.skip_ws()?;
        if !self.eat_keyword_with_dashes("ISO-10303-21") {
            return Err(P21Error::NotStep { line: self.line });
        }
        self.skip_ws()?;
        if self.b.get(self.pos) != Some(&b';') {
            return Err(P21Error::NotStep { line: self.line });
        }
        self.pos += 1;

        let mut file = P21File::default();
        let mut seen_data = false;
        loop {
            self.skip_ws()?;
            if self.pos >= self.b.len() {
                break;
            }
            let start = self.pos;
            let word = self.section_word();
            match word {
                "HEADER" => {
                    self.end_of_record()?;
                    self.header(&mut file)?;
                }
                "DATA" => {
                    self.skip_ws()?;
                    if self.b.get(self.pos) == Some(&b'(') {
                        self.pos += 1;
                        self.list_items()?;
                    }
                    self.end_of_record()?;
                    self.data(&mut file)?;
                    seen_data = true;
                }
                "ANCHOR" | "REFERENCE" | "SIGNATURE" => {
                    self.end_of_record()?;
                    self.skip_section()?;
                }
                "END-ISO-10303-21" => {
                    self.end_of_record()?;
                    break;
                }
                _ => {
                    self.pos = start;
                    return Err(
                        self.unexpected("a section (HEADER, DATA, ENDSEC) or END-ISO-10303-21")
                    );
                }
            }
        }
        if !seen_data {
            return Err(P21Error::NoData { line: self.line });
        }
        file.schemas = file
            .header
            .iter()
            .find(|r| r.name == "FILE_SCHEMA")
            .and_then(|r| r.list_at(0))
            .map(|l| {
                l.iter()
                    .filter_map(|p| p.as_str().map(str::to_owned))
                    .collect()
            })
            .unwrap_or_default();
        file.file_name = file
            .header
            .iter()
            .find(|r| r.name == "FILE_NAME")
            .and_then(|r| r.str_at(0))
            .map(str::to_owned);
        Ok(file)
    }

    /// Reads `[A-Za-z0-9_-]*` at `pos` (section keywords contain dashes).
    fn section_word(&mut self) -> &'a str {
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

    fn eat_keyword_with_dashes(&mut self, word: &str) -> bool {
        let start = self.pos;
        if self.section_word() == word {
            true
        } else {
            self.pos = start;
            false
        }
    }

    fn header(&mut self, file: &mut P21File) -> Res<()> {
        loop {
            self.skip_ws()?;
            match self.b.get(self.pos) {
                None => return Err(self.eof("ENDSEC; closing the HEADER section")),
                Some(&c) if is_keyword_start(c) => {
                    let start = self.pos;
                    if self.section_word() == "ENDSEC" {
                        return self.end_of_record();
                    }
                    self.pos = start;
                    let record = self.record()?;
                    self.end_of_record()?;
                    file.header.push(record);
                }
                Some(_) => return Err(self.unexpected("a header entity or ENDSEC")),
            }
        }
    }

    fn data(&mut self, file: &mut P21File) -> Res<()> {
        loop {
            self.skip_ws()?;
            match self.b.get(self.pos) {
                None => return Err(self.eof("ENDSEC; closing the DATA section")),
                Some(b'#') => {
                    let entity = self.entity_instance()?;
                    let index = file.entities.len();
                    if let Some(&first) = file.index.get(&entity.id) {
                        let first_line = file.entities.get(first).map_or(0, |e| e.line);
                        return Err(P21Error::DuplicateId {
                            line: entity.line,
                            entity: entity.id,
                            first_line,
                        });
                    }
                    file.index.insert(entity.id, index);
                    file.entities.push(entity);
                }
                Some(&c) if is_keyword_start(c) => {
                    let start = self.pos;
                    if self.section_word() == "ENDSEC" {
                        return self.end_of_record();
                    }
                    self.pos = start;
                    return Err(self.unexpected("'#' starting an entity instance, or ENDSEC"));
                }
                Some(_) => {
                    return Err(self.unexpected("'#' starting an entity instance, or ENDSEC"));
                }
            }
        }
    }

    /// Skips an edition-3 section that is not read, up to and including its `ENDSEC;`.
    fn skip_section(&mut self) -> Res<()> {
        loop {
            self.skip_ws()?;
            match self.b.get(self.pos) {
                None => return Err(self.eof("ENDSEC;")),
                Some(b'\'') => {
                    self.string()?;
                }
                Some(&c) if is_keyword_start(c) => {
                    if self.section_word() == "ENDSEC" {
                        return self.end_of_record();
                    }
                }
                Some(_) => self.pos += 1,
            }
        }
    }

    /// `#id = record;` or `#id = ( record record … );`, with `pos` at `#`.
    fn entity_instance(&mut self) -> Res<Entity> {
        let line = self.line;
        self.pos += 1;
        let id = self.digits_as_u64("an entity number after '#'")?;
        self.entity = Some(id);
        self.skip_ws()?;
        match self.b.get(self.pos) {
            Some(b'=') => self.pos += 1,
            None => return Err(self.eof("'='")),
            Some(_) => {
                return Err(P21Error::MissingEquals {
                    line: self.line,
                    entity: self.entity,
                    found: self.found(),
                });
            }
        }
        self.skip_ws()?;
        let parts = match self.b.get(self.pos) {
            Some(b'(') => {
                self.pos += 1;
                let mut parts = Vec::new();
                loop {
                    self.skip_ws()?;
                    match self.b.get(self.pos) {
                        Some(b')') => {
                            self.pos += 1;
                            break;
                        }
                        Some(&c) if is_keyword_start(c) => parts.push(self.record()?),
                        None => return Err(self.eof("')' closing the complex entity")),
                        Some(_) => {
                            return Err(
                                self.unexpected("an entity name or ')' in a complex entity")
                            );
                        }
                    }
                }
                if parts.is_empty() {
                    self.pos -= 1;
                    return Err(self.unexpected("an entity name in a complex entity"));
                }
                parts
            }
            Some(&c) if is_keyword_start(c) => vec![self.record()?],
            None => return Err(self.eof("an entity name")),
            Some(_) => return Err(self.unexpected("an entity name or '('")),
        };
        self.end_of_record()?;
        self.entity = None;
        Ok(Entity { id, line, parts })
    }

    /// Expects the `;` that ends a record or a section keyword.
    fn end_of_record(&mut self) -> Res<()> {
        let line = self.line;
        self.skip_ws()?;
        match self.b.get(self.pos) {
            Some(b';') => {
                self.pos += 1;
                Ok(())
            }
            None => Err(self.eof("';'")),
            Some(_) => Err(P21Error::MissingSemicolon {
                line,
                entity: self.entity,
                found: self.found(),
            }),
        }
    }

    /// `NAME(args)`, with `pos` at the first letter of the name.
    fn record(&mut self) -> Res<Record> {
        let name = self.keyword();
        self.skip_ws()?;
        match self.b.get(self.pos) {
            Some(b'(') => self.pos += 1,
            None => return Err(self.eof("'(' after the entity name")),
            Some(_) => return Err(self.unexpected("'(' after the entity name")),
        }
        let args = self.list_items()?;
        Ok(Record { name, args })
    }

    /// Reads a keyword at `pos` (which is a keyword start) and returns it in upper case.
    fn keyword(&mut self) -> String {
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

    /// The items of a list whose `(` has been consumed, up to and including its `)`.
    fn list_items(&mut self) -> Res<Vec<Param>> {
        if self.depth >= MAX_NESTING {
            return Err(P21Error::TooDeep {
                line: self.line,
                entity: self.entity,
            });
        }
        self.depth += 1;
        let mut items = Vec::new();
        self.skip_ws()?;
        if self.b.get(self.pos) == Some(&b')') {
            self.pos += 1;
            self.depth -= 1;
            return Ok(items);
        }
        loop {
            items.push(self.param()?);
            self.skip_ws()?;
            match self.b.get(self.pos) {
                Some(b',') => self.pos += 1,
                Some(b')') => {
                    self.pos += 1;
                    break;
                }
                None => return Err(self.eof("')' closing a list")),
                Some(_) => {
                    return Err(P21Error::UnterminatedList {
                        line: self.line,
                        entity: self.entity,
                        found: self.found(),
                    });
                }
            }
        }
        self.depth -= 1;
        Ok(items)
    }

    fn param(&mut self) -> Res<Param> {
        self.skip_ws()?;
        let Some(&c) = self.b.get(self.pos) else {
            return Err(self.eof("a parameter"));
        };
        match c {
            b'\'' => self.string().map(Param::Str),
            b'"' => self.binary(),
            b'#' => {
                self.pos += 1;
                self.digits_as_u64("an entity number after '#'")
                    .map(Param::Ref)
            }
            b'$' => {
                self.pos += 1;
                Ok(Param::Unset)
            }
            b'*' => {
                self.pos += 1;
                Ok(Param::Derived)
            }
            b'(' => {
                self.pos += 1;
                self.list_items().map(Param::List)
            }
            b'.' => self.enumeration(),
            b'0'..=b'9' | b'+' | b'-' => self.number(),
            c if is_keyword_start(c) => {
                let name = self.keyword();
                self.skip_ws()?;
                match self.b.get(self.pos) {
                    Some(b'(') => self.pos += 1,
                    None => return Err(self.eof("'(' after a type name")),
                    Some(_) => return Err(self.unexpected("'(' after a type name")),
                }
                let mut values = self.list_items()?;
                let value = if values.len() == 1 {
                    values.pop().unwrap_or(Param::Unset)
                } else {
                    Param::List(values)
                };
                Ok(Param::Typed(name, Box::new(value)))
            }
            b';' => Err(P21Error::UnterminatedList {
                line: self.line,
                entity: self.entity,
                found: self.found(),
            }),
            _ => Err(self.unexpected("a parameter")),
        }
    }

    /// Decimal digits at `pos` as an entity number.
    fn digits_as_u64(&mut self, expected: &'static str) -> Res<u64> {
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
    fn number(&mut self) -> Res<Param> {
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
    fn enumeration(&mut self) -> Res<Param> {
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
    fn binary(&mut self) -> Res<Param> {
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
    fn string(&mut self) -> Res<String> {
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
    fn skip_ws(&mut self) -> Res<()> {
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
    fn found(&self) -> String {
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

    fn unexpected(&self, expected: &'static str) -> P21Error {
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

    fn eof(&self, expected: &'static str) -> P21Error {
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
    use super::*;

    const MODELS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/models/");
    const FILES: [&str; 5] = [
        "as1-oc-214.stp",
        "NIST_MBE_PMI_3.stp",
        "NIST_MBE_PMI_11.stp",
        "nist_ctc_01_asme1_rd.stp",
        "screw.step",
    ];

    fn model(name: &str) -> String {
        std::fs::read_to_string(format!("{MODELS}{name}")).expect("model file is readable")
    }

    fn wrap(data: &str) -> String {
        format!(
            "ISO-10303-21;\nHEADER;\nFILE_SCHEMA(('TEST'));\nENDSEC;\nDATA;\n{data}\nENDSEC;\n\
             END-ISO-10303-21;\n"
        )
    }

    fn err(data: &str) -> P21Error {
        parse(&wrap(data)).expect_err("the text is malformed")
    }

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
    fn header_schema_and_file_name() {
        let file = parse(&model("as1-oc-214.stp")).expect("parses");
        assert_eq!(
            file.schemas,
            ["AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }"]
        );
        assert_eq!(file.file_name.as_deref(), Some("Open CASCADE Shape Model"));
        let file = parse(&model("NIST_MBE_PMI_11.stp")).expect("parses");
        assert_eq!(file.schemas, ["CONFIG_CONTROL_DESIGN"]);
        assert_eq!(file.file_name.as_deref(), Some("NI3147~1"));
    }

    #[test]
    fn records_lines_and_complex_entities_of_a_real_file() {
        let file = parse(&model("as1-oc-214.stp")).expect("parses");
        let e = file.get(748).expect("#748 exists");
        assert_eq!(e.line, 929);
        assert_eq!(
            e.type_name(),
            "REPRESENTATION_RELATIONSHIP+REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION+\
             SHAPE_REPRESENTATION_RELATIONSHIP"
        );
        let rr = e.part("REPRESENTATION_RELATIONSHIP").expect("part");
        assert_eq!(rr.ref_at(2), Some(62));
        assert_eq!(rr.ref_at(3), Some(44));
        assert!(e.has("SHAPE_REPRESENTATION_RELATIONSHIP"));
        assert_eq!(
            e.part("SHAPE_REPRESENTATION_RELATIONSHIP")
                .map(|r| r.args.len()),
            Some(0)
        );
        let p = file.get(16).expect("#16").record().expect("record");
        assert_eq!(p.name, "CARTESIAN_POINT");
        let xyz: Vec<f64> = p
            .list_at(1)
            .expect("list")
            .iter()
            .filter_map(Param::as_f64)
            .collect();
        assert_eq!(xyz, [-10.0, 75.0, 60.0]);
        // A string broken over two lines loses its line break.
        let file = parse(&model("nist_ctc_01_asme1_rd.stp")).expect("parses");
        let r = file.get(11).expect("#11").record().expect("record");
        assert_eq!(
            r.str_at(1),
            Some("relationship between nist_ctc_01_asme1_rd-None and nist_ctc_01_asme1_rd-None")
        );
        // Typed parameters inside argument lists.
        let file = parse(&model("NIST_MBE_PMI_3.stp")).expect("parses");
        let m = file.get(2473).expect("#2473").record().expect("record");
        assert_eq!(
            m.arg(0),
            Some(&Param::Typed(
                "LENGTH_MEASURE".into(),
                Box::new(Param::Real(2.54))
            ))
        );
        assert_eq!(m.f64_at(0), Some(2.54));
    }

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
    fn bom_leading_space_comments_and_several_data_sections() {
        let text = "\u{feff}  /* lead */\r\nISO-10303-21;\r\nHEADER;ENDSEC;\r\nDATA;#1=A();ENDSEC;\
                    DATA('x',('S'));\n#2=B(#1);ENDSEC;END-ISO-10303-21;trailing junk";
        let file = parse(text).expect("parses");
        assert_eq!(file.len(), 2);
        assert_eq!(file.get(2).map(|e| e.line), Some(5));
        assert!(file.schemas.is_empty());
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
    fn error_not_a_step_file() {
        let e = parse("\n\nHELLO;").expect_err("not STEP");
        assert_eq!(e, P21Error::NotStep { line: 3 });
        assert!(parse("").is_err());
        assert!(parse("ISO-10303-21").is_err());
    }

    #[test]
    fn error_no_data_section() {
        let e = parse("ISO-10303-21;\nHEADER;\nENDSEC;\nEND-ISO-10303-21;\n").expect_err("no data");
        assert_eq!(e, P21Error::NoData { line: 4 });
        assert_eq!(e.to_string(), "line 4: no DATA section");
        assert_eq!(e.reason(), "no DATA section");
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
    fn error_unterminated_list() {
        let e = err("#1=A();\n#455=B(1,\n(2,3);");
        assert_eq!(e.line(), 8);
        assert_eq!(e.entity(), Some(455));
        assert_eq!(
            e.to_string(),
            "line 8, entity #455: expected ')' or ',' in argument list, found ';'"
        );
        assert_eq!(
            e.reason(),
            "entity #455: expected ')' or ',' in argument list, found ';'"
        );
        let e = err("#1=A(1 2);");
        assert!(
            matches!(
                e,
                P21Error::UnterminatedList {
                    line: 6,
                    entity: Some(1),
                    ..
                }
            ),
            "{e}"
        );
    }

    #[test]
    fn error_missing_semicolon() {
        let e = err("#1=A()\n#2=B();");
        assert_eq!(
            e,
            P21Error::MissingSemicolon {
                line: 6,
                entity: Some(1),
                found: "'#2'".into()
            }
        );
    }

    #[test]
    fn error_missing_equals() {
        let e = err("#1=A();\n#2 B();");
        assert_eq!(
            e,
            P21Error::MissingEquals {
                line: 7,
                entity: Some(2),
                found: "'B'".into()
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

    #[test]
    fn error_duplicate_id() {
        let e = err("#1=A();\n#2=B();\n#1=C();");
        assert_eq!(
            e,
            P21Error::DuplicateId {
                line: 8,
                entity: 1,
                first_line: 6
            }
        );
    }

    #[test]
    fn error_unexpected_end_of_file() {
        let text = wrap("#1=A((1,2),'x');");
        let cut = text.find("2)").expect("cut point");
        let e = parse(&text[..cut]).expect_err("truncated");
        assert!(
            matches!(
                e,
                P21Error::UnexpectedEof {
                    line: 6,
                    entity: Some(1),
                    ..
                }
            ),
            "{e}"
        );
        let e = parse("ISO-10303-21;\nHEADER;\nENDSEC;\nDATA;\n#1=A();\n").expect_err("no ENDSEC");
        assert!(
            matches!(
                e,
                P21Error::UnexpectedEof {
                    line: 6,
                    entity: None,
                    ..
                }
            ),
            "{e}"
        );
    }

    #[test]
    fn error_nesting_too_deep() {
        let data = format!("#1=A({}{});", "(".repeat(1000), ")".repeat(1000));
        assert!(matches!(err(&data), P21Error::TooDeep { line: 6, .. }));
    }

    #[test]
    fn error_other_tokens() {
        assert!(matches!(err("#1=A(%);"), P21Error::Unexpected { .. }));
        assert!(matches!(err("#1=();"), P21Error::Unexpected { .. }));
        assert!(matches!(err("#1=A(.T);"), P21Error::Unexpected { .. }));
        assert!(matches!(err("#=A();"), P21Error::Unexpected { .. }));
        assert!(matches!(err("X;"), P21Error::Unexpected { .. }));
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
