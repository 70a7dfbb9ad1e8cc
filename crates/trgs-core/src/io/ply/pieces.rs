//! Reading a PLY file a piece at a time. A binary splat file (its vertices first, every vertex
//! property a scalar, as every 3DGS tool writes) is read in pieces of whole vertex rows, so that a
//! model of millions of Gaussians is not held twice. Any other file (ASCII, an element with
//! lists before the vertices, a header that does not parse) is read whole and left to
//! [`super::parse_ply`]. Both ways give the same values and the same messages (data after the
//! declared elements is refused either way), which
//! `tests::reading_in_pieces_is_parsing_whole` checks.
use std::fs::File;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

use super::body::Body;
use super::end::check_end;
use super::header::{Format, Header, parse_header};
use super::{Layout, VertexRows, parse_ply};
use crate::io::FormatError;
use crate::io::bytes::{ByteReader, Endian};
use crate::scene::Gaussians;

/// Vertex rows per piece: a few MiB at SH degree 3, small beside the Gaussians themselves.
pub(super) const ROWS_PER_PIECE: usize = 1 << 14;

/// A header longer than this is left to the whole-file parser (and its messages).
const HEADER_LIMIT: u64 = 1 << 20;

pub(super) fn read_in_pieces(
    path: &Path,
    rows_per_piece: usize,
) -> Result<Gaussians<f32>, FormatError> {
    let io = |e: std::io::Error| FormatError::io(path, &e);
    let fail = |m: String| FormatError::new(path, m);
    let mut file = BufReader::new(File::open(path).map_err(io)?);
    let len = file.get_ref().metadata().map_err(io)?.len();
    let mut bytes = header_lines(&mut file).map_err(io)?;
    let Some((header, vertex_index, endian)) = vertices_in_pieces(&bytes) else {
        file.read_to_end(&mut bytes).map_err(io)?;
        return parse_ply(&bytes, path);
    };
    let vertex = &header.elements[vertex_index];
    let layout = Layout::of(vertex).map_err(fail)?;
    let row_bytes: usize = vertex.properties.iter().map(|p| p.ty.size()).sum();
    let body_start = header.body_offset;
    let remaining = usize::try_from(len).unwrap_or(usize::MAX).saturating_sub(body_start);
    let mut rows = VertexRows::new(vertex, &layout, remaining);
    let mut piece = Vec::with_capacity(rows_per_piece.saturating_mul(row_bytes));
    let (mut i, mut offset) = (0u64, body_start);
    while i < vertex.count {
        let n = (vertex.count - i).min(rows_per_piece as u64);
        piece.clear();
        // A short piece is the end of the file; the row that runs past it reports the truncation.
        (&mut file).take(n * row_bytes as u64).read_to_end(&mut piece).map_err(io)?;
        let mut body = Body::Binary(ByteReader::at(&piece, offset), endian);
        for _ in 0..n {
            rows.read(&mut body, i).map_err(fail)?;
            i += 1;
        }
        offset += piece.len();
    }
    // The rest: the elements declared after the vertices, and nothing else.
    piece.clear();
    file.read_to_end(&mut piece).map_err(io)?;
    let mut body = Body::Binary(ByteReader::at(&piece, offset), endian);
    let after = &header.elements[vertex_index + 1..];
    check_end(&mut body, after, &header.elements).map_err(fail)?;
    Ok(rows.g)
}

/// The file's lines up to and including the `end_header` line, or fewer when the file ends
/// first or the header runs past [`HEADER_LIMIT`].
fn header_lines(file: &mut impl BufRead) -> std::io::Result<Vec<u8>> {
    let mut bytes = Vec::new();
    loop {
        let start = bytes.len();
        let room = HEADER_LIMIT.saturating_sub(start as u64);
        if room == 0 || file.take(room).read_until(b'\n', &mut bytes)? == 0 {
            return Ok(bytes);
        }
        let words: Vec<&[u8]> =
            bytes[start..].split(u8::is_ascii_whitespace).filter(|w| !w.is_empty()).collect();
        if words == [b"end_header"] {
            return Ok(bytes);
        }
    }
}

/// The header, the vertex element's index and the byte order, when the body can be read in
/// pieces of vertex rows: binary, every element before the vertices empty, and every vertex
/// property a scalar.
pub(super) fn vertices_in_pieces(header_bytes: &[u8]) -> Option<(Header, usize, Endian)> {
    let header = parse_header(header_bytes).ok()?;
    let Format::Binary(endian) = header.format else { return None };
    if header.body_offset != header_bytes.len() {
        return None;
    }
    let index = header.elements.iter().position(|e| e.name == "vertex")?;
    let before_empty =
        header.elements[..index].iter().all(|e| e.count == 0 || e.properties.is_empty());
    let scalars = header.elements[index].properties.iter().all(|p| p.list_count.is_none());
    (before_empty && scalars).then_some((header, index, endian))
}
