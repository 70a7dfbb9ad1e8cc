//! File formats. Every reader names the file and what was expected when input is malformed;
//! every writer writes a temporary file and renames it into place.
mod error;

pub use error::{FormatError, write_atomic};
