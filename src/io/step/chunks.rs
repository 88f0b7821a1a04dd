//! truck's view of a STEP file's entity instances, parsed in parallel.
//!
//! ruststep's parser (nom, one pass over the whole exchange structure) was the slowest single
//! step of reading a STEP file: about 40 % of loading a KiCad board assembly, on one core.
//! Entity instances are independent statements, so the text is cut at statement ends (`;`
//! outside strings and comments) into chunks of whole instances, each chunk parsed by
//! ruststep's own `entity_instance_list` on rayon, and the lists joined in file order.
//!
//! Guarantee: the same instances, in the same order, as ruststep's whole-file parse — when any
//! chunk does not parse to its end, the whole file is parsed as before (so an error is still
//! ruststep's own). The overall structure (`ISO-10303-21;`, `HEADER`, `DATA` sections) is not
//! checked here: our own scanner ([`super::p21`]) has read the file first.

use rayon::prelude::*;
use truck_stepio::r#in::ruststep;
use truck_stepio::r#in::ruststep::ast::EntityInstance;

/// Smallest chunk worth a task, bytes.
const MIN_CHUNK: usize = 64 * 1024;

/// The entity instances of every `DATA` section, in file order (see the module doc). `text`
/// must be only what our scanner read ([`super::p21::P21File::end`]): what follows
/// `END-ISO-10303-21;` (a second file appended, say) was not checked and must never reach
/// ruststep and truck.
pub(crate) fn entity_instances(text: &str) -> Result<Vec<EntityInstance>, String> {
    let statements = statements(text);
    let chunks = chunks(text, &statements, rayon::current_num_threads() * 4);
    let parsed: Option<Vec<Vec<EntityInstance>>> = chunks
        .par_iter()
        .map(|c| {
            // Isolated on the worker that runs it: a parser panic (ruststep overflows on some
            // numbers) is quiet here and makes the chunk fail, and the whole-file parse below
            // (isolated by the caller) reports it — no panic hook sees it on a rayon thread.
            match crate::isolate::isolated(|| ruststep::parser::exchange::entity_instance_list(c)) {
                Ok(Ok((rest, list))) if rest.trim().is_empty() => Some(list),
                _ => None,
            }
        })
        .collect();
    match parsed {
        Some(lists) if !chunks.is_empty() => Ok(lists.into_iter().flatten().collect()),
        _ => whole_file(text),
    }
}

/// ruststep's own parse of the whole exchange structure.
pub(crate) fn whole_file(text: &str) -> Result<Vec<EntityInstance>, String> {
    let exchange = ruststep::parser::parse(text).map_err(|e| e.to_string())?;
    Ok(exchange.data.into_iter().flat_map(|s| s.entities).collect())
}

/// Runs of consecutive entity instances (`#id = …;`), cut into about `parts` chunks of whole
/// instances (none smaller than [`MIN_CHUNK`] unless a run is); a chunk never spans a
/// statement that is not an instance (`ENDSEC;`, `DATA;`). `statements` are `text`'s
/// ([`statements`]).
fn chunks<'a>(text: &'a str, statements: &[(&'a str, bool)], parts: usize) -> Vec<&'a str> {
    let instance_bytes: usize = statements.iter().filter(|s| s.1).map(|s| s.0.len()).sum();
    let target = (instance_bytes / parts.max(1)).max(MIN_CHUNK);
    let mut out = Vec::new();
    let mut open: Option<(usize, usize)> = None;
    for (range, instance) in statements.iter().map(|(s, i)| (span(text, s), *i)) {
        match (open, instance) {
            (Some((start, _)), true) => open = Some((start, range.1)),
            (None, true) => open = Some(range),
            (Some((start, end)), false) => {
                out.push(&text[start..end]);
                open = None;
            }
            (None, false) => {}
        }
        if let Some((start, end)) = open
            && end - start >= target
        {
            out.push(&text[start..end]);
            open = None;
        }
    }
    if let Some((start, end)) = open {
        out.push(&text[start..end]);
    }
    out
}

/// Byte range of `s`, a slice of `text`.
fn span(text: &str, s: &str) -> (usize, usize) {
    let start = s.as_ptr() as usize - text.as_ptr() as usize;
    (start, start + s.len())
}

/// Every statement of the file (text up to and including a `;` outside strings and
/// comments, leading whitespace and comments left out), and whether it is an entity instance
/// (starts with `#`).
fn statements(text: &str) -> Vec<(&str, bool)> {
    let bytes = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    let mut start: Option<usize> = None;
    while i < bytes.len() {
        match bytes[i] {
            b'/' if bytes.get(i + 1) == Some(&b'*') => {
                // A comment: skipped (before a statement it is not part of it).
                i = text[i + 2..]
                    .find("*/")
                    .map_or(bytes.len(), |k| i + 2 + k + 2);
                continue;
            }
            b'\'' => {
                start.get_or_insert(i);
                // A string: '' is a quote inside it.
                i += 1;
                while i < bytes.len() {
                    if bytes[i] == b'\'' {
                        if bytes.get(i + 1) == Some(&b'\'') {
                            i += 2;
                            continue;
                        }
                        break;
                    }
                    i += 1;
                }
            }
            b';' => {
                let s = start.take().unwrap_or(i);
                let statement = &text[s..=i];
                out.push((statement, statement.starts_with('#')));
            }
            c if c.is_ascii_whitespace() => {}
            _ => {
                start.get_or_insert(i);
            }
        }
        i += 1;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const FILE: &str = "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION(('a;b'),'2;1');\n\
        FILE_NAME('f','2024',('a'),('b'),'c','d','e');\nFILE_SCHEMA(('S'));\nENDSEC;\n\
        DATA;\n#1=CARTESIAN_POINT('it is; /* not */ a comment',(0.,1.,2.));\n/* c; */ #2=A(#1);\n\
        #3=(B(1) C('x;'));\nENDSEC;\nDATA;\n#4=D($,*,.T.);\nENDSEC;\nEND-ISO-10303-21;\n";

    #[test]
    fn statements_end_at_semicolons_outside_strings_and_comments() {
        let s: Vec<&str> = statements(FILE).iter().map(|s| s.0).collect();
        assert_eq!(s[2], "FILE_DESCRIPTION(('a;b'),'2;1');");
        assert_eq!(
            s[7],
            "#1=CARTESIAN_POINT('it is; /* not */ a comment',(0.,1.,2.));"
        );
        assert_eq!(s[8], "#2=A(#1);");
        assert_eq!(s[9], "#3=(B(1) C('x;'));");
        let instances = statements(FILE).iter().filter(|s| s.1).count();
        assert_eq!(instances, 4);
        // '' is a quote inside a string (ruststep itself refuses such strings: the whole
        // file is then parsed, and refused, as before).
        let quoted: Vec<&str> = statements("#1=A('it''s; x');#2=B();")
            .iter()
            .map(|s| s.0)
            .collect();
        assert_eq!(quoted, ["#1=A('it''s; x');", "#2=B();"]);
    }

    #[test]
    fn chunks_hold_whole_instances_and_parse_as_the_whole_file() {
        // One chunk per instance run (MIN_CHUNK is far above this file), cut at ENDSEC.
        let c = chunks(FILE, &statements(FILE), 8);
        assert_eq!(c.len(), 2, "{c:?}");
        assert!(
            c[0].starts_with("#1=") && c[0].ends_with("C('x;'));"),
            "{c:?}"
        );
        assert_eq!(c[1], "#4=D($,*,.T.);");
        let whole = whole_file(FILE).expect("ruststep parses it");
        assert_eq!(whole.len(), 4);
        assert_eq!(entity_instances(FILE), Ok(whole));
    }

    #[test]
    fn a_chunk_that_does_not_parse_falls_back_to_the_whole_file() {
        let bad = FILE.replace("#2=A(#1);", "#2=A(#1;");
        let err = entity_instances(&bad).expect_err("ruststep refuses it");
        assert_eq!(Err(err), whole_file(&bad));
    }
}
