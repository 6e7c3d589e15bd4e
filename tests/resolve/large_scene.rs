//! A large scene RIB (mostly geometry, one shading network) is resolved without holding several
//! copies of it in memory: the reader keeps one copy of the input, and the
//! writer streams the untouched parts from it into the output file.
//!
//! The default run uses a 64 MB scene (fast enough for CI) and only checks that the output is
//! complete; the peak-memory check needs Linux's `/proc` and runs when it is available. For the
//! 1 GB measurement recorded in BENCHMARKS.md: `VSTRUCTC_LARGE_SCENE_MB=1024 cargo test --release
//! --test resolve large_scene -- --nocapture`.

use std::io::Write;
use std::path::Path;
use std::process::Command;
use std::time::Duration;

/// Writes a scene of about `megabytes` MB: the layered example, then geometry blocks.
fn write_scene(path: &Path, megabytes: usize) -> usize {
    let example = std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/examples/layered.rib"))
        .expect("examples/layered.rib");
    let mut out = std::io::BufWriter::new(std::fs::File::create(path).expect("create scene"));
    out.write_all(&example).expect("write");
    let row: String = (0..3000)
        .map(|i| format!("{:.4} ", (i % 97) as f32 / 97.0))
        .collect();
    let block = format!(
        "AttributeBegin\n  PointsPolygons [3] [0 1 2] \"P\" [\n{}]\nAttributeEnd\n",
        format!("{row}\n").repeat(20)
    );
    let mut written = example.len();
    while written < megabytes << 20 {
        out.write_all(block.as_bytes()).expect("write");
        written += block.len();
    }
    out.flush().expect("flush");
    written
}

/// Peak resident memory of process `pid` in bytes (`VmHWM`), if `/proc` has it.
fn peak_rss(pid: u32) -> Option<u64> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

#[test]
fn large_scene_is_streamed_with_one_copy_in_memory() {
    let megabytes: usize = std::env::var("VSTRUCTC_LARGE_SCENE_MB")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(64);
    let dir = std::env::temp_dir().join(format!("vstructc-large-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let input = dir.join("scene.rib");
    let output = dir.join("resolved.rib");
    let size = write_scene(&input, megabytes);

    let mut child = Command::new(env!("CARGO_BIN_EXE_vstructc"))
        .arg("resolve")
        .arg(&input)
        .arg("-o")
        .arg(&output)
        .spawn()
        .expect("run vstructc");
    // VmHWM only grows, so the last reading before the process exits is its peak.
    let mut peak = None;
    let status = loop {
        if let Some(p) = peak_rss(child.id()) {
            peak = Some(p);
        }
        if let Some(status) = child.try_wait().expect("wait") {
            break status;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    assert!(status.success(), "vstructc resolve failed: {status}");
    let out_len = std::fs::metadata(&output).expect("output").len() as usize;
    // The network is rewritten (a few hundred bytes more); everything else is copied.
    assert!(
        out_len >= size && out_len < size + 64 * 1024,
        "{out_len} vs {size}"
    );
    let scene_tail = read_tail(&input, 1 << 20);
    assert_eq!(
        read_tail(&output, 1 << 20),
        scene_tail,
        "geometry copied verbatim"
    );
    match peak {
        Some(peak) => {
            eprintln!(
                "scene {size} bytes, peak RSS {peak} bytes ({:.2}× the input)",
                peak as f64 / size as f64
            );
            // One copy of the input plus the network and the process itself; a second copy
            // (an output buffered in memory) would exceed this.
            assert!(
                peak < size as u64 + size as u64 / 4 + (32 << 20),
                "peak RSS {peak} for a {size}-byte scene: more than one copy held"
            );
        }
        None => crate::common::not_run("/proc not available: peak memory not checked"),
    }
    let _ = std::fs::remove_dir_all(&dir);
}

fn read_tail(path: &Path, n: usize) -> Vec<u8> {
    let bytes = std::fs::read(path).expect("read");
    bytes[bytes.len().saturating_sub(n)..].to_vec()
}
