//! Reports of runs as data: the per-frame CSV tables and the summary figures of
//! `patchwork implode` and `patchwork bench --flythrough`.
//!
//! Data in, text or numbers out; nothing here prints. Writing goes through
//! [`crate::io::png::write_text`] (atomic).

pub mod flythrough;
pub mod implode;
pub mod scale;
pub mod text;

/// A CSV table: `header`, then `row` of every record, each line ending in a newline.
fn table<T>(header: &str, records: &[T], row: impl Fn(&T) -> String) -> String {
    let mut csv = String::from(header);
    csv.push('\n');
    for r in records {
        csv.push_str(&row(r));
        csv.push('\n');
    }
    csv
}
