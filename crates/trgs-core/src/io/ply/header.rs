//! The PLY header: format, elements and their properties, and where the body starts.
use crate::io::bytes::Endian;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Format {
    Ascii,
    Binary(Endian),
}

/// PLY scalar types; both the classic names (`float`) and the sized aliases (`float32`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum ScalarType {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl ScalarType {
    fn parse(name: &str) -> Option<Self> {
        Some(match name {
            "char" | "int8" => Self::I8,
            "uchar" | "uint8" => Self::U8,
            "short" | "int16" => Self::I16,
            "ushort" | "uint16" => Self::U16,
            "int" | "int32" => Self::I32,
            "uint" | "uint32" => Self::U32,
            "float" | "float32" => Self::F32,
            "double" | "float64" => Self::F64,
            _ => return None,
        })
    }

    /// Bytes of a value in a binary body.
    pub(super) fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }

    pub(super) fn is_integer(self) -> bool {
        !matches!(self, Self::F32 | Self::F64)
    }
}

#[derive(Debug)]
pub(super) struct Property {
    pub name: String,
    /// The value type (of each item, for a list).
    pub ty: ScalarType,
    /// For a list property, the type of its leading item count.
    pub list_count: Option<ScalarType>,
}

#[derive(Debug)]
pub(super) struct Element {
    pub name: String,
    pub count: u64,
    pub properties: Vec<Property>,
}

#[derive(Debug)]
pub(super) struct Header {
    pub format: Format,
    pub elements: Vec<Element>,
    /// Offset of the first byte after the `end_header` line.
    pub body_offset: usize,
}

/// Parse the header lines up to `end_header`. Messages name the header line (1-based).
pub(super) fn parse_header(bytes: &[u8]) -> Result<Header, String> {
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut pos = 0;
    let mut number = 0;
    loop {
        let Some(len) = bytes[pos..].iter().position(|&b| b == b'\n') else {
            return Err(if number == 0 {
                "not a PLY file: it does not start with the line `ply`".into()
            } else {
                "the header has no `end_header` line".into()
            });
        };
        let raw = &bytes[pos..pos + len];
        pos += len + 1;
        number += 1;
        // Tolerate CRLF headers as written on Windows.
        let line = String::from_utf8_lossy(raw.strip_suffix(b"\r").unwrap_or(raw)).into_owned();
        if number == 1 {
            if line != "ply" {
                return Err("not a PLY file: it does not start with the line `ply`".into());
            }
            continue;
        }
        let at = |m: String| format!("header line {number}: {m}");
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            [] | ["comment", ..] | ["obj_info", ..] => {}
            ["end_header"] => break,
            ["format", f, _version] => {
                if format.is_some() {
                    return Err(at("a second `format` line".into()));
                }
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::Binary(Endian::Little),
                    "binary_big_endian" => Format::Binary(Endian::Big),
                    other => {
                        return Err(at(format!(
                            "unsupported format {other:?} (expected ascii, binary_little_endian or \
                             binary_big_endian)"
                        )));
                    }
                });
            }
            ["element", name, count] => {
                let count = count
                    .parse()
                    .map_err(|_| at(format!("element count {count:?} is not a number")))?;
                elements.push(Element { name: name.to_string(), count, properties: Vec::new() });
            }
            ["property", rest @ ..] => {
                let element = elements
                    .last_mut()
                    .ok_or_else(|| at("a property before any element".into()))?;
                let ty = |name: &str| {
                    ScalarType::parse(name)
                        .ok_or_else(|| at(format!("unknown property type {name:?}")))
                };
                let property = match rest {
                    ["list", count, item, name] => {
                        let count = ty(count)?;
                        if !count.is_integer() {
                            return Err(at(format!(
                                "list count type {count:?} is not an integer type"
                            )));
                        }
                        Property { name: name.to_string(), ty: ty(item)?, list_count: Some(count) }
                    }
                    [t, name] => Property { name: name.to_string(), ty: ty(t)?, list_count: None },
                    _ => return Err(at(format!("malformed property line {line:?}"))),
                };
                element.properties.push(property);
            }
            _ => return Err(at(format!("unexpected header line {line:?}"))),
        }
    }
    let format = format.ok_or("the header has no `format` line")?;
    Ok(Header { format, elements, body_offset: pos })
}
