//! Unit tests of `front::source` (`src/front/source.rs`).

use std::io;
use std::path::Path;
use vstructc::front::source::*;

#[test]
fn sizes_read_as_people_write_them() {
    assert_eq!(human_size(12), "12 B");
    assert_eq!(human_size(64 << 20), "64 MiB");
    assert_eq!(human_size((64 << 20) + 1), "64.0 MiB");
    assert_eq!(human_size(3 << 29), "1.5 GiB");
}

#[test]
fn an_endless_stream_stops_at_the_limit() {
    let err = read_stream(io::repeat(0), 1000).unwrap_err();
    assert!(matches!(
        err,
        ReadError::TooLarge {
            size: 1000,
            limit: 1000,
            at_least: true
        }
    ));
    assert_eq!(
        err.to_string(),
        "more than the limit of 1000 B (1000 bytes)",
        "{err}"
    );
    assert_eq!(read_stream(&[7u8; 1000][..], 1000).unwrap().len(), 1000);
}

#[test]
fn only_regular_files_within_the_limit_are_read() {
    let dir = std::env::temp_dir().join(format!("vstructc-source-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let f = dir.join("f");
    std::fs::write(&f, [1u8; 100]).unwrap();
    assert_eq!(read_regular_file(&f, 100).unwrap().len(), 100);
    let err = read_regular_file(&f, 99).unwrap_err();
    assert!(
        matches!(err, ReadError::TooLarge { size: 100, .. }),
        "{err}"
    );
    let err = read_regular_file(&dir, 99).unwrap_err();
    assert!(
        matches!(err, ReadError::NotRegular { kind: "a folder" }),
        "{err}"
    );
    #[cfg(unix)]
    {
        let err = read_regular_file(Path::new("/dev/zero"), 99).unwrap_err();
        assert!(
            matches!(
                err,
                ReadError::NotRegular {
                    kind: "a character device"
                }
            ),
            "{err}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
