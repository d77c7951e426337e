//! Hashing adapters for streaming an entry's payload: [`HashingWriter`] hashes (blake3) and counts every byte
//! on its way into the entry file, [`HashingReader`] hashes every byte read out of it and stops at the
//! payload's end. Each byte is hashed exactly once, in blocks of [`BLOCK_BYTES`] while the block is still in
//! the CPU cache from the copy (a 48 MB image is read from memory once, not once per pass); blocks are hashed
//! on the rayon pool. The digest equals blake3 of the whole payload whatever the block boundaries.

use std::io::{self, Read, Write};

use crate::hashing::{ContentHash, RAYON_THRESHOLD_BYTES};

/// Largest block passed to one `write`/`read` call and hashed at once.
pub(crate) const BLOCK_BYTES: usize = 2 << 20;

fn hash_block(hasher: &mut blake3::Hasher, block: &[u8]) {
    if block.len() >= RAYON_THRESHOLD_BYTES {
        hasher.update_rayon(block);
    } else {
        hasher.update(block);
    }
}

/// Forwards writes to `inner`, hashing and counting the bytes written.
pub(crate) struct HashingWriter<W: Write> {
    inner: W,
    hasher: blake3::Hasher,
    written: u64,
}

impl<W: Write> HashingWriter<W> {
    pub fn new(inner: W) -> Self {
        HashingWriter {
            inner,
            hasher: blake3::Hasher::new(),
            written: 0,
        }
    }

    /// Bytes written and their blake3.
    pub fn finish(self) -> (u64, ContentHash) {
        (self.written, self.hasher.finalize().into())
    }
}

impl<W: Write> Write for HashingWriter<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let block = &buf[..buf.len().min(BLOCK_BYTES)];
        let n = self.inner.write(block)?;
        hash_block(&mut self.hasher, &block[..n]);
        self.written += n as u64;
        Ok(n)
    }
    fn flush(&mut self) -> io::Result<()> {
        self.inner.flush()
    }
}

/// Reads at most `len` bytes from `inner`, hashing them. A read error is kept (see [`HashingReader::error`])
/// so the caller can tell a failing disk from bytes a decoder rejects.
pub(crate) struct HashingReader<R: Read> {
    inner: R,
    hasher: blake3::Hasher,
    remaining: u64,
    error: Option<io::Error>,
}

impl<R: Read> HashingReader<R> {
    pub fn new(inner: R, len: u64) -> Self {
        HashingReader {
            inner,
            hasher: blake3::Hasher::new(),
            remaining: len,
            error: None,
        }
    }

    /// Bytes of the payload not read yet.
    pub fn remaining(&self) -> u64 {
        self.remaining
    }

    /// The first read error met, if any.
    pub fn error(&self) -> Option<&io::Error> {
        self.error.as_ref()
    }

    /// Reads (and hashes) whatever the consumer left unread. Stops early at end of file or on an error.
    pub fn drain(&mut self) {
        let mut scratch = vec![0u8; BLOCK_BYTES.min(self.remaining as usize)];
        while self.remaining > 0 && self.error.is_none() {
            match self.read(&mut scratch) {
                Ok(0) => break,
                Ok(_) => {}
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(_) => break,
            }
        }
    }

    /// blake3 of the bytes read.
    pub fn finish(self) -> ContentHash {
        self.hasher.finalize().into()
    }
}

impl<R: Read> Read for HashingReader<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let want = (buf.len() as u64)
            .min(self.remaining)
            .min(BLOCK_BYTES as u64) as usize;
        if want == 0 {
            return Ok(0);
        }
        match self.inner.read(&mut buf[..want]) {
            Ok(n) => {
                hash_block(&mut self.hasher, &buf[..n]);
                self.remaining -= n as u64;
                Ok(n)
            }
            Err(e) if e.kind() == io::ErrorKind::Interrupted => Err(e),
            Err(e) => {
                let copy = io::Error::new(e.kind(), e.to_string());
                self.error.get_or_insert(e);
                Err(copy)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pattern(len: usize) -> Vec<u8> {
        (0..len)
            .map(|i| (i.wrapping_mul(2654435761) >> 9) as u8)
            .collect()
    }

    #[test]
    fn digests_equal_blake3_of_the_whole_payload_for_any_split() {
        let data = pattern(2 * BLOCK_BYTES + 12_345);
        let expected = ContentHash::from(blake3::hash(&data));
        for split in [0, 1, 1000, BLOCK_BYTES - 1, BLOCK_BYTES + 7] {
            let mut out = Vec::new();
            let mut w = HashingWriter::new(&mut out);
            w.write_all(&data[..split]).unwrap();
            w.write_all(&data[split..]).unwrap();
            assert_eq!(w.finish(), (data.len() as u64, expected), "split {split}");
            assert_eq!(out, data);

            let mut r = HashingReader::new(data.as_slice(), data.len() as u64);
            let mut first = vec![0u8; split];
            r.read_exact(&mut first).unwrap();
            assert_eq!(r.remaining(), (data.len() - split) as u64);
            r.drain();
            assert_eq!(r.remaining(), 0);
            assert_eq!(r.finish(), expected, "split {split}");
        }
    }

    #[test]
    fn reader_stops_at_the_payload_end_and_reports_short_input() {
        let data = pattern(100);
        let mut r = HashingReader::new(data.as_slice(), 60);
        let mut all = Vec::new();
        r.read_to_end(&mut all).unwrap();
        assert_eq!(all, &data[..60]);
        assert_eq!(r.finish(), ContentHash::from(blake3::hash(&data[..60])));
        // Announced 200, source holds 100: drain ends with bytes missing, no error, no hang.
        let mut r = HashingReader::new(data.as_slice(), 200);
        r.drain();
        assert_eq!((r.remaining(), r.error().is_none()), (100, true));
    }

    #[test]
    fn read_errors_are_kept() {
        struct Failing;
        impl Read for Failing {
            fn read(&mut self, _: &mut [u8]) -> io::Result<usize> {
                Err(io::Error::other("disk on fire"))
            }
        }
        let mut r = HashingReader::new(Failing, 10);
        assert!(r.read(&mut [0u8; 4]).is_err());
        r.drain();
        assert_eq!(r.error().unwrap().to_string(), "disk on fire");
    }
}
