//! Property tests: the `.oso` reader never panics, whatever the bytes.

use proptest::prelude::*;
use vstructc::Diagnostics;
use vstructc::front::oso::parse_oso;

/// A small but realistic `.oso` document that the mutations start from.
const SEED: &str = "OpenShadingLanguage 1.00\n\
# comment\n\
shader S\t%meta{string,help,\"h, {x}\"}\n\
param\tfloat[2]\tf\t1 2\t\t%meta{float[2],minmax,0,1} %read{1,2}\n\
param\tstring\ts\t\"a\\\\\\\"b\"\t%meta{string,vstructmember,\"h.m\"}\n\
param\tcolor\tc\t\\\n 1 1 1\t%initexpr\n\
param\tstruct T\tt\t\t%struct{\"T\"}\n\
param\tfloat\tt.x\t0\n\
oparam\tclosure color\tCi\n\
oparam\tfloat\to\t0\t%meta{string,vstructConditionalExpr,\"connect if a == \\\"b\\\"\"}\n\
const\tint\t$c\t1\n\
code ___main___\n\
\tend\n";

fn parse(bytes: &[u8]) {
    let mut diags = Diagnostics::new();
    let result = parse_oso(bytes, "fuzz.oso", &mut diags);
    // Every error carries a positioned diagnostic with an OS code.
    if let Err(e) = result {
        let d = e.diagnostic().expect("input errors carry a diagnostic");
        assert!(d.code.starts_with("OS"), "{}", d.code);
        assert!(
            d.location
                .as_ref()
                .is_some_and(|l| l.line > 0 && l.column > 0)
        );
    }
}

#[test]
fn seed_document_loads() {
    let mut diags = Diagnostics::new();
    let def = parse_oso(SEED.as_bytes(), "seed.oso", &mut diags).expect("seed loads");
    assert!(diags.is_empty(), "{diags:?}");
    assert_eq!(def.inputs.len(), 4);
    assert_eq!(def.outputs.len(), 2);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
        parse(&bytes);
    }

    #[test]
    fn random_oso_like_text_never_panics(
        body in proptest::collection::vec(
            prop_oneof![
                Just("param".to_string()), Just("oparam".to_string()), Just("float".to_string()),
                Just("struct".to_string()), Just("closure".to_string()), Just("[".to_string()),
                Just("]".to_string()), Just("%meta{".to_string()), Just("}".to_string()),
                Just(",".to_string()), Just("\"".to_string()), Just("\\".to_string()),
                Just("\n".to_string()), Just("\t".to_string()), Just(" ".to_string()),
                Just("#".to_string()), Just("%initexpr".to_string()), Just("-1".to_string()),
                Just("1e".to_string()), Just(".".to_string()), Just("x.y".to_string()),
                "[a-z0-9]{1,4}",
            ],
            0..64,
        )
    ) {
        let text = format!("OpenShadingLanguage 1.00\nshader S\n{}", body.concat());
        parse(text.as_bytes());
    }

    #[test]
    fn mutated_seed_never_panics(
        cut in 0..SEED.len(),
        insert in any::<u8>(),
        at in 0..SEED.len(),
    ) {
        let mut bytes = SEED.as_bytes().to_vec();
        bytes.insert(at, insert);
        parse(&bytes);
        parse(&SEED.as_bytes()[..cut]);
    }
}
