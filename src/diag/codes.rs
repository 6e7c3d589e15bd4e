//! Every diagnostic code with its documented meaning (the tables of `docs/`).

/// `(code, meaning)`, sorted by code.
pub(super) const CODES: &[(&str, &str)] = &[
    (
        "AR001",
        "not well-formed XML (with the position of the problem), or `<page>` nested more than 64 deep",
    ),
    ("AR002", "the root element is not `<args>`"),
    ("AR003", "a `<param>` or `<output>` has no `name`"),
    ("AR004", "two inputs, or two outputs, share a name"),
    (
        "AR005",
        "the file cannot be read, is not valid UTF-8, or declares an encoding other than UTF-8/ASCII (a warning for a missing `VSTRUCTC_ARGS_PATH` entry)",
    ),
    (
        "AR010",
        "the shader type is missing (warning: kind `unknown`) or not a known one (info: kept)",
    ),
    (
        "AR011",
        "a type is unknown or missing; the property is kept with an unknown type",
    ),
    (
        "AR012",
        "a default could not be read as written (the message gives the value used), has the wrong number of components, or has a trailing `f` (info)",
    ),
    (
        "AR013",
        "`arraySize` is not an integer (read as a scalar), cannot apply to the type, or exceeds 2^20 elements (read as a dynamic array)",
    ),
    (
        "AR014",
        "the `format` attribute of `<args>` is missing or not `1.0`; the file is read anyway",
    ),
    (
        "AR015",
        "`<sdrGlobalConfig>` after a property that uses `sdrDefinitionName`; the element is ignored and reading continues (the reference stops reading there)",
    ),
    (
        "AR020",
        "a deprecated form: the `tag` attribute, `<typeTag>`, `type` on an `<output>`, the `input` attribute; it is interpreted",
    ),
    ("AR021", "an unknown element; ignored"),
    (
        "AR022",
        "a `vstructConditionalExpr` on a property that is not a member; ignored",
    ),
    (
        "AR023",
        "(`args-child-meta`) a child metadata element conflicts with the attribute; the attribute wins",
    ),
    (
        "IO001",
        "a network or output file cannot be read or written (the operating system's message)",
    ),
    ("IO002", "the PNG encoder failed"),
    (
        "IO003",
        "the input is in a format vstructc recognises but does not read: MaterialX (`.mtlx`, or XML with a `<materialx>` root), or USD in a library built without its `usd` feature; the message names it",
    ),
    (
        "IR001",
        "a closure tree built in code is malformed (the message says what is wrong)",
    ),
    (
        "JS001",
        "not valid JSON (with line and column), or nested deeper than 128 levels",
    ),
    (
        "JS002",
        "a schema violation: a missing or mistyped required field, a duplicate key, a parameter object that is not `{ \"type\", \"value\" }`, an unknown type string",
    ),
    ("JS003", "an unsupported `vstructcNetwork` version"),
    ("JS004", "a value that does not match its declared type"),
    (
        "JS006",
        "a bare (shorthand) value for a parameter the registry does not declare",
    ),
    (
        "JS010",
        "a connection to a node that is not in the material; kept",
    ),
    ("JS011", "an unknown key, at any level; ignored"),
    (
        "LM001",
        "a bound of `Limits` was exceeded: the message names the limit, the value found and the maximum (a network input beyond `network_file_bytes`, more than `nodes` nodes, `params_per_node` parameters on one node or definition, `connections_per_input` connections on one input; for conditionals the same facts are reported as VS001)",
    ),
    (
        "LW001",
        "the terminal's shader type has no recipe (the message lists the supported ones)",
    ),
    (
        "LW002",
        "a parameter is connected to a node the lowering does not interpret; it becomes an external input slot with the parameter's value as fallback",
    ),
    (
        "LW003",
        "the registry has no definition of the shader; the recipe's built-in defaults are used",
    ),
    ("LW010", "the material needs more than 16 BSDF lobes"),
    ("LW011", "a cycle among interpreted patterns"),
    (
        "LW020",
        "a parameter the network sets (or a vstruct wrote) or connects is approximated or ignored although it has a visible effect (the message says how); once per material, node and parameter",
    ),
    (
        "LW021",
        "an unsupported lobe or effect with a non-zero or connected gain is dropped",
    ),
    (
        "LW022",
        "a constant outside its documented range was clamped",
    ),
    (
        "LW030",
        "an unresolved vstruct placeholder reached the lowering; it is ignored",
    ),
    (
        "OS001",
        "no `OpenShadingLanguage` header, no shader line, or an unknown shader type",
    ),
    (
        "OS002",
        "a malformed `param`/`oparam` line (unknown type, bad array size, …)",
    ),
    ("OS003", "an unterminated string or hint"),
    ("OS004", "two properties share a name"),
    (
        "OS010",
        "a default does not match the type (count or kind of values); no default",
    ),
    (
        "OS011",
        "a `%meta` entry with an unknown type or malformed values; ignored",
    ),
    (
        "OS012",
        "a vstruct key in `%meta` with a type other than `string`; ignored",
    ),
    (
        "OS013",
        "the header's version is newer than the newest tested (1.00); read anyway",
    ),
    ("RB001", "gzip-compressed RIB; decompress it first"),
    (
        "RB002",
        "binary RIB (a byte above 0x7F outside a string or comment, with its offset)",
    ),
    ("RB003", "an unterminated string"),
    (
        "RB004",
        "an unexpected character or token, a nested or unterminated array, a shading request without its shader or handle string",
    ),
    ("RB005", "an array mixing numbers and strings"),
    (
        "RB006",
        "an empty parameter declaration, or one without a type that the definition does not declare",
    ),
    ("RB007", "a parameter without a value"),
    (
        "RB008",
        "a connection string with an empty output name (`\"handle:\"`)",
    ),
    (
        "RB010",
        "an unknown string escape, read as the character itself",
    ),
    (
        "RB011",
        "a single-quoted string (an error with `--strict-rib`)",
    ),
    (
        "RB012",
        "a declaration without a type; the definition's type is used",
    ),
    (
        "RB013",
        "an unknown type word (or unknown leading words) in a declaration",
    ),
    (
        "RB014",
        "a value or connection count that does not match the type, or numbers on a `reference` parameter; kept as written",
    ),
    (
        "RB015",
        "a parameter given twice on one request; the later wins",
    ),
    (
        "RB016",
        "a parameter's declared type differs from the definition's (not checked on placeholders)",
    ),
    (
        "RB017",
        "a handle is redefined; later references bind to the new version",
    ),
    (
        "RB018",
        "a reference to a handle not defined earlier; kept as a dangling connection",
    ),
    (
        "RB019",
        "the node's shader is not in the registry; its parameters are kept verbatim (reported by the RIB reader alone; `pipeline::run` and the commands report VS020 instead)",
    ),
    (
        "RB020",
        "a legacy shading request with `reference` parameters; passed through, not resolved",
    ),
    (
        "RB021",
        "a shading request longer than 4 GiB (from its keyword to its last value)",
    ),
    (
        "RG001",
        "a second definition of the same kind with the same id is ignored (a note when it only shadows a built-in definition)",
    ),
    (
        "RG002",
        "an id exists as both `.oso` and `.args`; the message says which one is used (`--prefer`)",
    ),
    (
        "RG003",
        "a symbolic link in a definitions folder leads back to a folder above it (not followed), or a folder is reached a second time by another way (a note; skipped)",
    ),
    (
        "RG004",
        "an entry named like a definition file is a FIFO, a device or a socket: not read (an error for an explicit path)",
    ),
    (
        "US001",
        "the USD stage cannot be opened or composed (a layer that is not USD, a malformed layer, an unreadable file); the message gives the reason, and for a `.usda` root layer the line and column where reading stops",
    ),
    (
        "US002",
        "a composition problem (an unresolvable reference, payload or sublayer: the prims it would bring are missing), or a connection or terminal to a prim that is not a Shader on the stage; the connection is kept dangling",
    ),
    (
        "US003",
        "a Shader without `info:id`, or implemented otherwise (`info:implementationSource` is `sourceAsset` or `sourceCode`); kept as a node of unknown type",
    ),
    (
        "US004",
        "inputs with time samples: the default values are used (one warning per stage, naming the first such input and their number)",
    ),
    (
        "US005",
        "a connection to a NodeGraph or Material port that is neither connected nor given a value, or that passes 64 ports (a cycle); left out",
    ),
    (
        "US006",
        "a value of a type vstructc does not read (quaternions, 2×2 and 3×3 matrices, dictionaries, …) or that cannot be read; the parameter is left out",
    ),
    (
        "VS001",
        "a conditional does not parse; the message names the offending token and what was expected, with its position inside the expression (an error for `vstructc expr`)",
    ),
    (
        "VS002",
        "a conditional sits on an input member; only output members' conditionals are ever used",
    ),
    (
        "VS003",
        "a malformed `vstructmember` (no dot, or an empty head or member part); the property is not a member",
    ),
    (
        "VS004",
        "two output members of one head share a name (or alias); the one declared later wins",
    ),
    (
        "VS005",
        "a head name has both input and output members; they form a separate input head and output head",
    ),
    (
        "VS006",
        "a `vstructmemberaliases` value contains whitespace or a comma; it is still used as one alias",
    ),
    (
        "VS007",
        "a head has members but no property of that name is declared (it works anyway)",
    ),
    (
        "VS008",
        "a member is itself a head of other members (nested vstruct); it is not expanded again (extension `nested`)",
    ),
    (
        "VS009",
        "a conditional reads (or copies) a name that is not an input of its node type, including names with `[n]`",
    ),
    (
        "VS010",
        "a placeholder cannot be resolved (upstream node missing, its type unknown, its output not an output head, or a whole-node reference); the placeholder is kept",
    ),
    (
        "VS011",
        "a head has more than one connection; only the first is expanded, all are deleted (the message lists the dropped ones)",
    ),
    (
        "VS012",
        "cycle: an upstream node is still being resolved and is used as it is",
    ),
    (
        "VS013",
        "a `set` was not applied: the destination is not declared, has a type `set` cannot write, or string/number do not match",
    ),
    (
        "VS014",
        "a `copy` was not applied (missing definition or input, type mismatch), or was applied across an array/scalar shape mismatch",
    ),
    (
        "VS015",
        "a comparison was false only because of a missing operand, a type mismatch, a token operand or an ordering operator on strings",
    ),
    (
        "VS016",
        "a member was not expanded because its conditional does not parse (once per use)",
    ),
    (
        "VS017",
        "an authored value on an input head was removed after resolution",
    ),
    (
        "VS018",
        "an authored value on a member was overridden by `connect`, `set` or `copy`",
    ),
    (
        "VS019",
        "a member was already connected; the direct connection wins over the expansion",
    ),
    (
        "VS020",
        "a node type is not in the registry (once per type, naming its nodes and the closest known ids): a warning when one of its nodes feeds an input head or the id looks like a misspelling of a known one, an info otherwise; its nodes' parameters are kept verbatim and not checked",
    ),
    (
        "VS021",
        "a downstream member has no upstream counterpart (normal; shown with `--verbose`)",
    ),
    (
        "VS022",
        "`--no-conditions` connected members whose conditional is `set`, `copy`, `ignore` or unparsable: one info with their number and the first (with `--verbose`, a note for each)",
    ),
    (
        "VS023",
        "a `set` of a number outside the 32-bit integer range into an `int` member; the value was saturated",
    ),
    (
        "VS024",
        "an authored parameter is not an input (or input head) of its node's definition, or a connection names an output the upstream definition does not declare; the message gives the closest declared names (`__` names are the renderer's and not checked)",
    ),
];
