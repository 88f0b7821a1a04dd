//! The grammar of the Part 21 scanner (ISO 10303-21:2016): the exchange
//! structure (`ISO-10303-21;`, `HEADER`, `DATA` sections, skipped edition-3 sections,
//! `END-ISO-10303-21;`), entity instances (simple and complex records), and parameter lists
//! nested at most [`MAX_NESTING`] deep. Tokens come from `lexer`.

use super::lexer::is_keyword_start;
use super::{Entity, MAX_NESTING, P21Error, P21File, Param, Parser, Record, Res};

impl<'a> Parser<'a> {
    pub(super) fn file(&mut self) -> Res<P21File> {
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
            file.end = self.pos;
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
                    file.end = self.pos;
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
}

#[cfg(test)]
mod tests {
    use super::super::fixtures::{err, model, wrap};
    use super::super::parse;
    use super::*;

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
    fn bom_leading_space_comments_and_several_data_sections() {
        let text = "\u{feff}  /* lead */\r\nISO-10303-21;\r\nHEADER;ENDSEC;\r\nDATA;#1=A();ENDSEC;\
                    DATA('x',('S'));\n#2=B(#1);ENDSEC;END-ISO-10303-21;trailing junk";
        let file = parse(text).expect("parses");
        assert_eq!(file.len(), 2);
        assert_eq!(file.get(2).map(|e| e.line), Some(5));
        assert!(file.schemas.is_empty());
    }

    #[test]
    fn error_not_a_step_file() {
        let e = parse("\n\nHELLO;").expect_err("not STEP");
        assert_eq!(e, P21Error::NotStep { line: 3 });
        assert!(parse("").is_err());
        assert!(parse("ISO-10303-21").is_err());
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
}
