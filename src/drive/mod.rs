//! Drivers of the one frame loop ([`crate::frame::step`]): a recorded camera path through the
//! LOD loop (`bench --flythrough`) and an assembly animation (`implode`). They produce records;
//! [`crate::report`] turns them into tables and plots.

pub mod flythrough;
pub mod implode;
pub mod scale;
