//! A PFM reader for the image tests: the format `vstructc render --pfm` writes.

/// A decoded PFM: width, height, pixels top row first.
pub struct Pfm {
    pub w: usize,
    pub h: usize,
    pub px: Vec<[f32; 3]>,
}

pub fn read_pfm(bytes: &[u8]) -> Pfm {
    // Header: "PF\n<w> <h>\n<scale>\n", then little-endian f32 RGB rows, bottom row first.
    let mut lines = 0;
    let mut end = 0;
    for (i, b) in bytes.iter().enumerate() {
        if *b == b'\n' {
            lines += 1;
            if lines == 3 {
                end = i + 1;
                break;
            }
        }
    }
    let header = std::str::from_utf8(&bytes[..end]).unwrap();
    let mut it = header.split_whitespace();
    assert_eq!(it.next(), Some("PF"));
    let w: usize = it.next().unwrap().parse().unwrap();
    let h: usize = it.next().unwrap().parse().unwrap();
    let scale: f32 = it.next().unwrap().parse().unwrap();
    assert!(scale < 0.0, "little-endian PFM has a negative scale");
    let body = &bytes[end..];
    assert_eq!(body.len(), w * h * 12, "PFM body size");
    let f = |k: usize| f32::from_le_bytes(body[4 * k..4 * k + 4].try_into().unwrap());
    let mut px = vec![[0.0; 3]; w * h];
    for row in 0..h {
        // File row `row` is image row h − 1 − row.
        for x in 0..w {
            let k = (row * w + x) * 3;
            px[(h - 1 - row) * w + x] = [f(k), f(k + 1), f(k + 2)];
        }
    }
    Pfm { w, h, px }
}
