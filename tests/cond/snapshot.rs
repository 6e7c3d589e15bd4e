//! Snapshots of AST dumps and error renderings (reviewed by hand against spec/vstruct.md §3).

use vstructc::cond::{self, Extension, Extensions};

/// (snapshot name, expression, extensions)
const ASTS: &[(&str, &str, &[Extension])] = &[
    ("ast_01_connect", "connect", &[]),
    ("ast_02_ignore", "ignore", &[]),
    ("ast_03_set_negative_fraction", "set -.5", &[]),
    ("ast_04_set_string", "set 'abc'", &[]),
    ("ast_05_set_empty_string", "set \"\"", &[]),
    ("ast_06_copy", "copy diffuseGain", &[]),
    ("ast_07_copy_array_name", "copy a[1]", &[]),
    ("ast_08_if_else", "if x == 1 else ignore", &[]),
    ("ast_09_is_not_set", "x is not set", &[]),
    ("ast_10_is_set", "x is set", &[]),
    ("ast_11_glued_minus", "connect if x==-1", &[]),
    ("ast_12_double_parens", "connect if ((x == 1))", &[]),
    ("ast_13_keyword_is_name", "connect if is is connected", &[]),
    ("ast_14_keyword_connect_name", "connect == 1", &[]),
    ("ast_15_set_is_set", "set is set", &[]),
    ("ast_16_if_is_is_set", "if is is set else ignore", &[]),
    ("ast_17_else_name", "connect if else == 1 else ignore", &[]),
    ("ast_18_tabs", "connect\tif\tx == 1", &[]),
    (
        "ast_19_trailing_space",
        "connect if enableDiffuse == 1 ",
        &[],
    ),
    ("ast_20_ignore_if", "ignore if x == 1", &[]),
    (
        "ast_21_set_if_else_set",
        "set 1 if enableDiffuse == 1 else set 0",
        &[],
    ),
    (
        "ast_22_ignore_if_else_set",
        "ignore if x == 1 else set 0",
        &[],
    ),
    (
        "ast_23_copy_if_else_set",
        "copy x if y == 'a' else set 'b'",
        &[],
    ),
    (
        "ast_24_set_floats",
        "set 1.0 if enableRR == 1 else set 0.0",
        &[],
    ),
    ("ast_25_or_and", "a == 1 or b == 1 and c == 1", &[]),
    ("ast_26_and_or", "a == 1 and b == 1 or c == 1", &[]),
    ("ast_27_numbers", "x > .5 and y <= 5. or z >= 1e2", &[]),
    ("ast_28_verbatim_string", "s == 'a\\'b'", &[]),
    ("ast_29_if_name", "if == 1", &[]),
    ("ast_30_if_is_set", "if is set", &[]),
    ("ast_31_copy_is_connected", "copy is connected", &[]),
    (
        "ast_32_mixer_bump",
        "connect if (baselayer_enableSpecular == 1 and baselayer_specularBumpNormal is connected) or  (layer1_enableSpecular == 1 and layer1_specularBumpNormal is connected) ",
        &[],
    ),
    (
        "ast_33_laika_nested",
        "set 1 if ( MaterialInput_ClearCoat_Enable == 1 or ( Enable == 1 and ClearCoat_Enable == 1 ) ) else set 0",
        &[],
    ),
    (
        "ast_34_else_if_chain",
        "set 1 if a == 1 else copy p if b is not connected else ignore if c != 'x'",
        &[Extension::ElseIf],
    ),
    (
        "ast_35_multiline_string",
        "s == \"two\nlines\" or t < -1e-3",
        &[],
    ),
    (
        "ast_36_chain_is_one_node",
        "a == 1 and b == 2 and c == 3 and d == 4",
        &[],
    ),
    (
        "ast_37_grouped_chains",
        "(a == 1 and b == 2) and c == 3 or d == 4 or (e == 5 or f == 6) or g == 7 and (h == 8 and i == 9)",
        &[],
    ),
];

/// (snapshot name, malformed expression)
const ERRORS: &[(&str, &str)] = &[
    ("err_01_empty", ""),
    ("err_02_blank", "   "),
    ("err_03_copy_if", "copy if"),
    ("err_04_single_equals", "connect if x = 1"),
    ("err_05_unary_not", "not x == 1"),
    ("err_06_param_vs_param", "x == y"),
    ("err_07_boolean_literal", "x == true"),
    ("err_08_plus_sign", "x == +1"),
    ("err_09_detached_minus", "x == - 1"),
    ("err_10_hex", "x == 0x10"),
    ("err_11_is_two_spaces", "x is  not connected"),
    ("err_12_is_notable", "x is notable"),
    ("err_13_upper_case", "CONNECT if x == 1"),
    (
        "err_14_chained_else_if",
        "connect if x == 1 else connect if y == 1",
    ),
    ("err_15_trailing_else", "connect if x == 1 else"),
    ("err_16_set_name", "set x"),
    ("err_17_copy_string", "copy 'x'"),
    ("err_18_dotted_name", "connect if x.y == 1"),
    ("err_19_namespaced", "connect if ns:x == 1"),
    ("err_20_semicolon", "connect if x == 1;"),
    ("err_21_unclosed_paren", "connect if (x == 1"),
    ("err_22_number_as_name", "connect if 007 == 7"),
    ("err_23_carriage_return", "connect if x == 1\r"),
    ("err_24_unterminated_string", "connect if x == 'abc"),
    ("err_25_spaced_index", "connect if arr[ 2] == 1"),
    ("err_26_if_without_else", "if x == 1"),
    ("err_27_and_and", "connect if x == 1 && y == 1"),
    ("err_28_non_ascii", "connect if größe == 1"),
    ("err_29_tab_before_error", "connect\tif\tx\t= 1"),
    ("err_30_second_line", "connect if x == 1 or\n  y === 2"),
];

fn ast_snapshot(text: &str, ext: &Extensions) -> String {
    let stmt = cond::parse_with(text, ext)
        .unwrap_or_else(|e| panic!("{text:?} should parse: {}", e.render(text)));
    let names = ext.names().join(",");
    format!(
        "input: {text:?}\nextensions: [{names}]\ndesugared: {stmt}\nparams: {:?}\n\n{}",
        stmt.param_names(),
        stmt.dump()
    )
}

fn error_snapshot(text: &str) -> String {
    let err = match cond::parse(text) {
        Ok(s) => panic!("{text:?} should fail, parsed as {s}"),
        Err(e) => e,
    };
    format!(
        "input: {text:?}\nspan: {:?}\nexpected: {:?}\n\n{}",
        err.span,
        err.expected,
        err.render(text)
    )
}

#[test]
fn ast_dumps() {
    assert!(ASTS.len() >= 30);
    for (name, text, ext) in ASTS {
        let ext: Extensions = ext.iter().copied().collect();
        insta::assert_snapshot!(*name, ast_snapshot(text, &ext));
    }
}

#[test]
fn error_renderings() {
    assert!(ERRORS.len() >= 15);
    for (name, text) in ERRORS {
        insta::assert_snapshot!(*name, error_snapshot(text));
    }
}

#[test]
fn diagnostic_rendering_of_a_definition_error() {
    // How a VS001 looks once the registry adds the attribute's location.
    let text = "connect if enableDiffuse = 1 ";
    let err = cond::parse(text).unwrap_err();
    let start = vstructc::Location::new("PxrLayer.args", 120, 41);
    let d = err
        .to_diagnostic(text)
        .at(cond::internals::location_in(&start, text, err.span.start));
    insta::assert_snapshot!("diag_vs001_in_definition", d.render_human());
}

#[test]
fn json_shape_of_chains() {
    // The `statement` member of `vstructc expr --json`: an `and`/`or` chain is one node with
    // its `terms` in order; a parenthesised chain on the right is a nested node.
    let stmt = cond::parse("connect if a == 1 and b is set and (c < 2 or d != 'x')").unwrap();
    let json = serde_json::to_string_pretty(&stmt).unwrap();
    insta::assert_snapshot!("json_chain_shape", json);
}
