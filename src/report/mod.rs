//! Reports of runs as data: the per-frame CSV tables and the summary figures of
//! `patchwork implode` and `patchwork bench --flythrough`.
//!
//! Data in, text or numbers out; nothing here prints. Writing goes through
//! [`crate::io::png::write_text`] (atomic).

pub mod flythrough;
pub mod implode;
