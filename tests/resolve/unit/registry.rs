//! Unit tests of `registry` (`src/registry/mod.rs`).

use vstructc::registry::*;

#[test]
fn registry_is_send_and_sync() {
    fn check<T: Send + Sync>() {}
    check::<Registry>();
    check::<VstructTables>();
}

#[test]
fn oso_name_is_peeked_from_the_shader_line() {
    let dir = std::env::temp_dir().join(format!("vstructc-peek-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let f = dir.join("file.oso");
    std::fs::write(
        &f,
        "# c\nOpenShadingLanguage 1.00\n# more\nshader MyShader %meta{}\n",
    )
    .unwrap();
    assert_eq!(peek_oso_name(&f).as_deref(), Some("MyShader"));
    std::fs::write(&f, "nonsense\n").unwrap();
    assert_eq!(peek_oso_name(&f), None);
    let _ = std::fs::remove_dir_all(&dir);
}
