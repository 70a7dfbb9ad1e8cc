//! The two containers of SPZ, opened into the attribute bytes they hold: versions 1-3 are one
//! gzip stream of a 16-byte header and the attributes in turn (extension records may follow);
//! version 4 is a plain 32-byte header, extension records, a table of stream sizes and one zstd
//! frame per attribute.
use flate2::read::GzDecoder;
use std::io::Read;

/// "NGSP", little-endian.
pub const MAGIC: u32 = 0x5053_474e;
/// Header flag: extension records are present.
const FLAG_HAS_EXTENSIONS: u8 = 0x2;
/// The extension that says which frame the data are stored in (Adobe's, in the reference).
const EXTENSION_COORDINATE_SYSTEM: u32 = 0xADBE_0003;
/// The reference's `CoordinateSystem` values of the two frames trgs reads.
const COORDINATES_UNSPECIFIED: u32 = 0;
const COORDINATES_RUB: u32 = 4;
const COORDINATES_RDF: u32 = 6;

/// The frame the file stores its Gaussians in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StoredFrame {
    /// Right-up-back: the reference's default.
    Rub,
    /// Right-down-forward, trgs's and the PLY's (by a coordinate-system extension).
    Rdf,
}

/// The attribute bytes of an SPZ file and what its header says about them.
#[derive(Debug)]
pub struct Packed {
    pub version: u32,
    pub count: usize,
    pub sh_degree: u32,
    pub fractional_bits: u8,
    pub frame: StoredFrame,
    pub positions: Vec<u8>,
    pub alphas: Vec<u8>,
    pub colours: Vec<u8>,
    pub scales: Vec<u8>,
    pub rotations: Vec<u8>,
    pub sh: Vec<u8>,
}

impl Packed {
    /// The attributes `parts` (positions, alphas, colours, scales, rotations, SH) with what the
    /// header says of them.
    fn new(h: Header, frame: StoredFrame, parts: impl IntoIterator<Item = Vec<u8>>) -> Self {
        let mut parts = parts.into_iter();
        let mut next = || parts.next().unwrap_or_default();
        Packed {
            version: h.version,
            count: h.count,
            sh_degree: h.sh_degree,
            fractional_bits: h.fractional_bits,
            frame,
            positions: next(),
            alphas: next(),
            colours: next(),
            scales: next(),
            rotations: next(),
            sh: next(),
        }
    }

    /// The byte count of each attribute (positions, alphas, colours, scales, rotations, SH).
    fn sizes(version: u32, count: usize, sh_degree: u32) -> Option<[usize; 6]> {
        let dim = ((sh_degree + 1) * (sh_degree + 1) - 1) as usize;
        let rotation = if version >= 3 { 4 } else { 3 };
        let per = [9, 1, 3, 3, rotation, 3 * dim];
        let mut out = [0; 6];
        for (o, p) in out.iter_mut().zip(per) {
            *o = count.checked_mul(p)?;
        }
        Some(out)
    }
}

/// The attributes of an SPZ file of version 2, 3 or 4.
pub fn open(bytes: &[u8]) -> Result<Packed, String> {
    if bytes.len() >= 4 && u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]) == MAGIC {
        return open_streams(bytes);
    }
    let mut raw = Vec::new();
    GzDecoder::new(bytes)
        .read_to_end(&mut raw)
        .map_err(|e| format!("{e}; expected an SPZ file (gzip, or \"NGSP\" and zstd streams)"))?;
    open_gzip_payload(&raw)
}

fn word(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

/// The header fields both containers share.
#[derive(Clone, Copy, Debug)]
struct Header {
    version: u32,
    count: usize,
    sh_degree: u32,
    fractional_bits: u8,
    flags: u8,
}

/// The header fields both containers share, checked.
fn header(b: &[u8], accepted: std::ops::RangeInclusive<u32>) -> Result<Header, String> {
    if b.len() < 16 || word(b, 0) != MAGIC {
        return Err("no SPZ header (expected the magic \"NGSP\")".into());
    }
    let (version, count) = (word(b, 4), word(b, 8) as usize);
    if !accepted.contains(&version) {
        return Err(format!("SPZ version {version}: trgs reads versions 2, 3 and 4"));
    }
    let degree = u32::from(b[12]);
    if degree > 3 {
        return Err(format!("SH degree {degree}: trgs models hold degrees 0 to 3"));
    }
    Ok(Header { version, count, sh_degree: degree, fractional_bits: b[13], flags: b[14] })
}

/// Versions 2 and 3: the gzip stream's content.
fn open_gzip_payload(raw: &[u8]) -> Result<Packed, String> {
    let h = header(raw, 2..=3)?;
    let (count, degree) = (h.count, h.sh_degree);
    let sizes = Packed::sizes(h.version, count, degree).ok_or("the Gaussian count overflows")?;
    let total = 16 + sizes.iter().sum::<usize>();
    let has_extensions = h.flags & FLAG_HAS_EXTENSIONS != 0;
    if raw.len() < total || (!has_extensions && raw.len() != total) {
        return Err(format!(
            "{} bytes after decompressing; {count} Gaussians of SH degree {degree} take {total}",
            raw.len()
        ));
    }
    let frame = if has_extensions { frame_of(&raw[total..])? } else { StoredFrame::Rub };
    let mut at = 16;
    let parts = sizes.map(|len| {
        let part = raw[at..at + len].to_vec();
        at += len;
        part
    });
    Ok(Packed::new(h, frame, parts))
}

/// Version 4: header, extensions up to the table of streams, then one zstd frame per attribute
/// (the SH stream left out at degree 0), ending exactly at the end of the file.
fn open_streams(b: &[u8]) -> Result<Packed, String> {
    if b.len() < 32 {
        return Err("an SPZ version 4 header is 32 bytes; the file is shorter".into());
    }
    let h = header(b, 4..=4)?;
    let (count, degree) = (h.count, h.sh_degree);
    let streams = usize::from(b[15]);
    let table = word(b, 16) as usize;
    let sizes = Packed::sizes(h.version, count, degree).ok_or("the Gaussian count overflows")?;
    let expected = sizes.iter().filter(|&&s| s > 0).count();
    if streams != expected {
        return Err(format!(
            "{streams} streams; {count} Gaussians of SH degree {degree} take {expected}"
        ));
    }
    if table < 32 || table + 16 * streams > b.len() {
        return Err(format!("the table of streams at byte {table} lies outside the file"));
    }
    let frame = if h.flags & FLAG_HAS_EXTENSIONS != 0 {
        frame_of(&b[32..table])?
    } else {
        StoredFrame::Rub
    };
    let mut at = table + 16 * streams;
    let mut out: Vec<Vec<u8>> = Vec::with_capacity(6);
    let mut entry = 0;
    for size in sizes {
        if size == 0 {
            out.push(Vec::new());
            continue;
        }
        let e = table + 16 * entry;
        entry += 1;
        let packed_len = u64::from_le_bytes(b[e..e + 8].try_into().map_err(|_| "table")?);
        let unpacked_len = u64::from_le_bytes(b[e + 8..e + 16].try_into().map_err(|_| "table")?);
        if unpacked_len != size as u64 {
            return Err(format!("stream {entry} holds {unpacked_len} bytes, {size} expected"));
        }
        let end = usize::try_from(packed_len).ok().and_then(|l| at.checked_add(l));
        let Some(end) = end.filter(|&e| e <= b.len()) else {
            return Err(format!("stream {entry} runs past the end of the file"));
        };
        let decoder = ruzstd::decoding::StreamingDecoder::new(&b[at..end])
            .map_err(|e| format!("stream {entry}: {e}"))?;
        let mut data = Vec::with_capacity(size);
        // A byte past the expected size is enough to refuse the stream: no more is inflated.
        decoder
            .take(size as u64 + 1)
            .read_to_end(&mut data)
            .map_err(|e| format!("stream {entry}: {e}"))?;
        if data.len() != size {
            return Err(format!(
                "stream {entry} decompresses to {} bytes, {size} expected",
                data.len()
            ));
        }
        out.push(data);
        at = end;
    }
    if at != b.len() {
        return Err(format!("{} bytes after the last stream", b.len() - at));
    }
    Ok(Packed::new(h, frame, out))
}

/// The stored frame that extension records `{type, length, payload}` name (right-up-back when
/// none does); a frame other than right-up-back or right-down-forward is refused by name.
fn frame_of(mut records: &[u8]) -> Result<StoredFrame, String> {
    let mut frame = StoredFrame::Rub;
    while records.len() >= 8 {
        let (kind, len) = (word(records, 0), word(records, 4) as usize);
        let Some(payload) = records.get(8..8 + len) else {
            return Err("an extension record runs past its data".into());
        };
        if kind == EXTENSION_COORDINATE_SYSTEM && payload.len() >= 4 {
            frame = match word(payload, 0) {
                COORDINATES_UNSPECIFIED | COORDINATES_RUB => StoredFrame::Rub,
                COORDINATES_RDF => StoredFrame::Rdf,
                other => {
                    return Err(format!(
                        "stored in coordinate system {other} of the reference's list; trgs reads \
                         RUB (4) and RDF (6)"
                    ));
                }
            };
        }
        records = &records[8 + len..];
    }
    Ok(frame)
}
