//! Measurement output for the pelage lab programs (`pelage lab ...` and
//! `pelage bench`, in `crates/pelage-cli`).
//!
//! - [`Table`]: CSV (RFC 4180 quoting) and an aligned plain-text table for
//!   the terminal.
//! - [`pareto_front`]: the Pareto-optimal points of a cost/error cloud.
//! - [`ScatterChart`]: "error against time" scatter plots with the Pareto
//!   front marked and marker area encoding a third quantity, written as a
//!   self-contained SVG or as a PNG, both drawn with `plotters` (its SVG and
//!   bitmap backends) and the bundled DejaVu Sans font: no system fonts, no
//!   C libraries, works headless.
//! - [`contact_sheet`]: images in a labelled grid, captions in the same font.
//! - [`write_file_atomically`] and [`AtomicFile`]: every file is written to a
//!   short temporary name and renamed, so an interrupted run never leaves a
//!   half-written result (devices are written through, symbolic links
//!   followed); the one atomic writer of pelage, also used by `pelage_scene`
//!   and the facade.

#![deny(missing_docs)]

pub mod atomic_file;
mod chart;
mod error;
mod font;
mod fs;
mod pareto;
mod sheet;
mod table;

pub use chart::{ScatterChart, ScatterPoint};
pub use error::LabError;
pub use fs::{
    AtomicFile, WriteError, create_dir, remove_pending_temporaries, remove_stale_temporaries,
    write_bytes_atomically, write_file_atomically,
};
pub use pareto::pareto_front;
pub use sheet::contact_sheet;
pub use table::Table;
