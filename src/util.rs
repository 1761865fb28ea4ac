//! Small helpers shared across the crate: hashing files and text, and names
//! safe to use as one folder component.

use sha2::{Digest, Sha256};
use std::io::Read;
use std::path::Path;

/// Lower-case hex of bytes.
pub fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// SHA-256 (hex) of some bytes.
pub fn sha256_hex(bytes: &[u8]) -> String {
    hex(&Sha256::digest(bytes))
}

/// SHA-256 (hex) of a file's content, streamed.
pub fn sha256_file(path: &Path) -> std::io::Result<String> {
    let mut f = std::fs::File::open(path)?;
    let mut h = Sha256::new();
    let mut buf = vec![0u8; 1 << 16];
    loop {
        let n = f.read(&mut buf)?;
        if n == 0 {
            break;
        }
        h.update(&buf[..n]);
    }
    Ok(hex(&h.finalize()))
}

/// Text made safe as a single path component: letters, digits, '-', '_'
/// and '+' are kept, every other run of characters becomes one '_', and the
/// result is cut to `max` characters. Never empty, never "." or "..", never
/// holds a separator: a folder named from it stays inside its parent.
pub fn safe_component(text: &str, max: usize) -> String {
    let mut out = String::new();
    let mut gap = false;
    for ch in text.chars() {
        if ch.is_ascii_alphanumeric() || matches!(ch, '-' | '_' | '+') {
            if gap && !out.is_empty() {
                out.push('_');
            }
            gap = false;
            out.push(ch);
        } else {
            gap = true;
        }
    }
    out.truncate(max);
    if out.is_empty() {
        out.push('_');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn safe_components_never_leave_their_folder() {
        assert_eq!(safe_component("ckpt:../../etc/x", 60), "ckpt_etc_x");
        assert_eq!(safe_component("..", 60), "_");
        assert_eq!(safe_component("heuristic", 60), "heuristic");
        assert_eq!(safe_component("a/b\\c d", 3), "a_b");
        assert_eq!(
            sha256_hex(b"abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }
}
