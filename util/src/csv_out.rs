//! Writing CSV files: one quoting rule for every text cell skytie writes, and an atomic writer of a header
//! plus rows. Readers (campaign-format.md) take a line starting with `#` for a comment and trim unquoted cells,
//! so such cells are quoted too.

use crate::fsutil::atomic_write_with;
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;

/// A CSV text cell (RFC 4180): quoted, with quotes doubled, when it holds a separator, a quote or a line break,
/// starts with `#`, or starts or ends with a space; otherwise as it is.
pub fn quote(s: &str) -> String {
    let needs_quotes = s.starts_with('#')
        || s.starts_with(' ')
        || s.ends_with(' ')
        || s.contains([',', '"', '\n', '\r']);
    if needs_quotes {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// Writes a CSV file atomically: the `header` row, then the rows `rows` writes.
pub fn write_csv<F>(path: &Path, header: &[&str], rows: F) -> io::Result<()>
where
    F: FnOnce(&mut BufWriter<&mut File>) -> io::Result<()>,
{
    atomic_write_with(path, |w| {
        writeln!(w, "{}", header.join(","))?;
        rows(w)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_cells_are_quoted_only_when_needed() {
        assert_eq!(quote("pano_001"), "pano_001");
        assert_eq!(quote("a,b"), "\"a,b\"");
        assert_eq!(quote("say \"hi\""), "\"say \"\"hi\"\"\"");
        assert_eq!(quote("#1"), "\"#1\"");
        assert_eq!(quote(" lead"), "\" lead\"");
        assert_eq!(quote("trail "), "\"trail \"");
        assert_eq!(quote("two\nlines"), "\"two\nlines\"");
        assert_eq!(quote("in # middle"), "in # middle");
    }

    #[test]
    fn the_header_comes_first_and_the_file_is_replaced_whole() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.csv");
        std::fs::write(&path, "old").unwrap();
        write_csv(&path, &["a", "b"], |w| writeln!(w, "1,{}", quote("x,y"))).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "a,b\n1,\"x,y\"\n");
    }
}
