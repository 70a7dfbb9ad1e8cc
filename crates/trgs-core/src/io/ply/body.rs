//! Reading scalar values from a PLY body, binary (either byte order) or ASCII.
use super::header::{Element, ScalarType};
use crate::io::bytes::{ByteReader, Endian};

/// A cursor over the body that yields every scalar as f64 (exact for every PLY type, f32
/// included, so a float property round-trips bit for bit through `as f32`).
pub(super) enum Body<'a> {
    Binary(ByteReader<'a>, Endian),
    Ascii(Tokens<'a>),
}

/// Whitespace-separated ASCII tokens; element instances need not be one a line.
pub(super) struct Tokens<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Iterator for Tokens<'a> {
    type Item = &'a [u8];

    fn next(&mut self) -> Option<&'a [u8]> {
        let rest = &self.bytes[self.pos..];
        let start = rest.iter().position(|b| !b.is_ascii_whitespace())?;
        let len =
            rest[start..].iter().position(u8::is_ascii_whitespace).unwrap_or(rest.len() - start);
        self.pos += start + len;
        Some(&rest[start..start + len])
    }
}

impl<'a> Body<'a> {
    pub(super) fn ascii(bytes: &'a [u8]) -> Self {
        Body::Ascii(Tokens { bytes, pos: 0 })
    }

    /// Bytes not yet read.
    pub(super) fn remaining(&self) -> usize {
        match self {
            Body::Binary(r, _) => r.remaining(),
            Body::Ascii(t) => t.bytes.len() - t.pos,
        }
    }

    /// The next value, of type `ty`; `what` names it in an error (made only then: a splat PLY
    /// holds tens of millions of values).
    pub(super) fn scalar(
        &mut self,
        ty: ScalarType,
        what: &dyn Fn() -> String,
    ) -> Result<f64, String> {
        match self {
            Body::Binary(r, e) => binary(r, *e, ty, what),
            Body::Ascii(tokens) => {
                let tok = tokens
                    .next()
                    .ok_or_else(|| format!("truncated: the data ends before {}", what()))?;
                let text = std::str::from_utf8(tok).unwrap_or("");
                let bad = || {
                    format!("{}: cannot read {:?} as {ty:?}", what(), String::from_utf8_lossy(tok))
                };
                let v = match ty {
                    // Parse f32 directly: going through f64 could round twice.
                    ScalarType::F32 => text.parse::<f32>().map(f64::from).map_err(|_| bad())?,
                    ScalarType::F64 => text.parse::<f64>().map_err(|_| bad())?,
                    _ => text.parse::<i64>().map(|v| v as f64).map_err(|_| bad())?,
                };
                Ok(v)
            }
        }
    }

    /// Read past every instance of `element` (list properties included).
    pub(super) fn skip(&mut self, element: &Element) -> Result<(), String> {
        // Nothing to read, however large its count.
        if element.properties.is_empty() {
            return Ok(());
        }
        for i in 0..element.count {
            for p in &element.properties {
                let what =
                    || format!("{} {i} of {}, property {}", element.name, element.count, p.name);
                let n = match p.list_count {
                    Some(ty) => self.count(ty, &what)?,
                    None => 1,
                };
                for _ in 0..n {
                    self.scalar(p.ty, &what)?;
                }
            }
        }
        Ok(())
    }

    /// What is left unread, in words ("12 bytes", "3 values on 1 line"), or None when nothing
    /// but whitespace in an ASCII body is.
    pub(super) fn left_over(&self) -> Option<String> {
        let plural = |n: usize, one: &str| format!("{n} {one}{}", if n == 1 { "" } else { "s" });
        match self {
            Body::Binary(r, _) => (r.remaining() > 0).then(|| plural(r.remaining(), "byte")),
            Body::Ascii(t) => {
                let rest = &t.bytes[t.pos..];
                let values = Tokens { bytes: rest, pos: 0 }.count();
                let lines = rest
                    .split(|&b| b == b'\n')
                    .filter(|l| l.iter().any(|b| !b.is_ascii_whitespace()))
                    .count();
                (values > 0)
                    .then(|| format!("{} on {}", plural(values, "value"), plural(lines, "line")))
            }
        }
    }

    /// The item count of a list property.
    pub(super) fn count(
        &mut self,
        ty: ScalarType,
        what: &dyn Fn() -> String,
    ) -> Result<u64, String> {
        let v = self.scalar(ty, what)?;
        if v < 0.0 || v.fract() != 0.0 {
            return Err(format!("{}: list count {v} is not a non-negative integer", what()));
        }
        Ok(v as u64)
    }
}

fn binary(
    r: &mut ByteReader<'_>,
    e: Endian,
    ty: ScalarType,
    what: &dyn Fn() -> String,
) -> Result<f64, String> {
    Ok(match ty {
        ScalarType::I8 => f64::from(i8::from_le_bytes(r.array_with(e, what)?)),
        ScalarType::U8 => f64::from(u8::from_le_bytes(r.array_with(e, what)?)),
        ScalarType::I16 => f64::from(i16::from_le_bytes(r.array_with(e, what)?)),
        ScalarType::U16 => f64::from(u16::from_le_bytes(r.array_with(e, what)?)),
        ScalarType::I32 => f64::from(i32::from_le_bytes(r.array_with(e, what)?)),
        ScalarType::U32 => f64::from(u32::from_le_bytes(r.array_with(e, what)?)),
        ScalarType::F32 => f64::from(f32::from_le_bytes(r.array_with(e, what)?)),
        ScalarType::F64 => f64::from_le_bytes(r.array_with(e, what)?),
    })
}
