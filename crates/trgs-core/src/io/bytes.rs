//! A bounds-checked little/big-endian cursor over a byte slice, shared by the binary readers
//! (COLMAP .bin, PLY). Every read either returns a value or a message that says what was being
//! read and where the data ran out; callers add the file and the record.

/// Byte order of a binary body.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Endian {
    Little,
    Big,
}

#[derive(Debug)]
pub(crate) struct ByteReader<'a> {
    bytes: &'a [u8],
    pos: usize,
    /// Where `bytes` starts in the file, so that messages give file offsets when the file is
    /// read a piece at a time.
    base: usize,
}

impl<'a> ByteReader<'a> {
    pub(crate) fn new(bytes: &'a [u8]) -> Self {
        Self::at(bytes, 0)
    }

    /// A reader of `bytes`, a piece of a file that starts at byte `base` of it.
    pub(crate) fn at(bytes: &'a [u8], base: usize) -> Self {
        Self { bytes, pos: 0, base }
    }

    pub(crate) fn remaining(&self) -> usize {
        self.bytes.len() - self.pos
    }

    /// The next `n` bytes, or a "truncated" message naming `what` was being read.
    pub(crate) fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        self.take_with(n, || what.to_string())
    }

    /// [`ByteReader::take`] with the name of what is read made only for the message: readers of
    /// millions of records (a splat PLY) name each value by its record.
    pub(crate) fn take_with(
        &mut self,
        n: usize,
        what: impl FnOnce() -> String,
    ) -> Result<&'a [u8], String> {
        if n > self.remaining() {
            return Err(format!(
                "truncated: the file ends at byte {} while reading {} ({n} bytes needed, {} left)",
                self.base + self.bytes.len(),
                what(),
                self.remaining()
            ));
        }
        let out = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        Ok(out)
    }

    /// The next `N` bytes in file order, reversed when the file's byte order is big endian, so
    /// that `from_le_bytes` decodes them either way.
    pub(crate) fn array<const N: usize>(
        &mut self,
        endian: Endian,
        what: &str,
    ) -> Result<[u8; N], String> {
        self.array_with(endian, || what.to_string())
    }

    /// [`ByteReader::array`] with `what` made only for the message ([`ByteReader::take_with`]).
    pub(crate) fn array_with<const N: usize>(
        &mut self,
        endian: Endian,
        what: impl FnOnce() -> String,
    ) -> Result<[u8; N], String> {
        let mut a = [0u8; N];
        a.copy_from_slice(self.take_with(N, what)?);
        if endian == Endian::Big {
            a.reverse();
        }
        Ok(a)
    }

    pub(crate) fn u8(&mut self, what: &str) -> Result<u8, String> {
        Ok(self.take(1, what)?[0])
    }

    pub(crate) fn i32(&mut self, what: &str) -> Result<i32, String> {
        self.array(Endian::Little, what).map(i32::from_le_bytes)
    }

    pub(crate) fn i64(&mut self, what: &str) -> Result<i64, String> {
        self.array(Endian::Little, what).map(i64::from_le_bytes)
    }

    pub(crate) fn u64(&mut self, what: &str) -> Result<u64, String> {
        self.array(Endian::Little, what).map(u64::from_le_bytes)
    }

    pub(crate) fn f64(&mut self, what: &str) -> Result<f64, String> {
        self.array(Endian::Little, what).map(f64::from_le_bytes)
    }

    /// Bytes up to (not including) the next NUL, which is consumed.
    pub(crate) fn nul_terminated(&mut self, what: &str) -> Result<&'a [u8], String> {
        let rest = &self.bytes[self.pos..];
        let len = rest.iter().position(|&b| b == 0).ok_or_else(|| {
            format!(
                "truncated: no NUL terminator after {what} (the file ends at byte {})",
                self.base + self.bytes.len()
            )
        })?;
        self.pos += len + 1;
        Ok(&rest[..len])
    }
}

/// A capacity for `count` records of at least `min_size` bytes each that the remaining data could
/// actually hold, so that a corrupt count cannot make us allocate terabytes before failing.
pub(crate) fn capacity_for(count: u64, min_size: usize, reader: &ByteReader<'_>) -> usize {
    let fits = reader.remaining() / min_size.max(1);
    usize::try_from(count).map_or(fits, |c| c.min(fits))
}
