//! The `vstructc` command line. The binary's `main` only calls [`main`];
//! each subcommand lives in its own module and returns an exit status.
//!
//! Exit status, the same in every command ([`EXIT_STATUS`]): 0 success (warnings on
//! stderr), 1 input errors (or warnings under `--deny-warnings`) or no material to act on
//! (`compile`, `render`, `eval`), 2 usage errors, found before the input is read.

use clap::{Parser, Subcommand, ValueEnum};
use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;
use vstructc::diag::{Diagnostics, Severity, Shown};
use vstructc::registry::Prefer;

/// `eprintln!` that ignores a failing standard error (`2>/dev/full`): the exit status still
/// says what happened, and there is nowhere left to say more. `eprintln!` would panic.
macro_rules! eprintln_quiet {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}

pub mod compile;
pub mod eval;
pub mod explain;
pub mod expr;
pub mod group;
pub mod info;
pub mod input;
pub mod json;
pub mod list;
pub mod material;
pub mod render;
pub mod resolve;
pub mod snippet;

/// The exit status rules, shown by `--help`: the same in every command.
pub const EXIT_STATUS: &str = "Exit status (every command): 0 success (warnings allowed), \
1 when the input has errors (or warnings under --deny-warnings) or holds no material to act \
on (compile, render, eval), 2 usage errors (found before the input is read). Machine output: \
--json on list, info, expr, resolve, explain, compile and eval (docs/json.md).";

/// Top-level command line.
#[derive(Debug, Parser)]
#[command(
    name = "vstructc",
    version,
    about = "Shader-network compiler: vstruct resolution, closure IR, previews",
    after_help = EXIT_STATUS
)]
pub struct Cli {
    /// Options shared by every subcommand.
    #[command(flatten)]
    pub common: CommonOptions,
    /// The subcommand.
    #[command(subcommand)]
    pub command: Command,
}

/// Options shared by every subcommand.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct CommonOptions {
    /// A definitions folder or file (`.args`, `.oso`); repeatable. Searched before
    /// `VSTRUCTC_ARGS_PATH` and the embedded definitions.
    #[arg(long = "args", value_name = "PATH", global = true)]
    pub args: Vec<PathBuf>,
    /// Which definition wins when a shader exists as both `.oso` and `.args`.
    #[arg(long, global = true, default_value = "oso", value_parser = prefer_parser())]
    pub prefer: Prefer,
    /// Enable an opt-in extension by name (repeatable, or comma-separated), or `all`.
    ///
    /// Every extension is off by default; without them behaviour is the reference's
    /// (docs/conditional-language.md, docs/resolution.md). An unknown name is a usage error.
    #[arg(long = "ext", value_name = "NAME", global = true, value_parser = ExtParser)]
    pub ext: Vec<String>,
    /// Treat warnings as errors (exit status 1 after printing every diagnostic).
    #[arg(long, global = true)]
    pub deny_warnings: bool,
    /// Diagnostic output format.
    #[arg(long, value_enum, global = true, default_value_t = DiagFormat::Human)]
    pub diag_format: DiagFormat,
    /// Also show `note` diagnostics.
    #[arg(long, short, global = true)]
    pub verbose: bool,
    /// Show at most N diagnostics of each code, then one line counting the rest; 0 shows
    /// all. Default: 20 in human output, no limit in JSON output. Human output shows
    /// identical diagnostics (same code, place and message) once, and those of the same
    /// message shape on different nodes as one naming how many nodes.
    #[arg(long, value_name = "N", global = true)]
    pub max_diagnostics: Option<usize>,
    /// Colour human diagnostics: `auto` when standard error is a terminal and `NO_COLOR` is
    /// unset or empty.
    #[arg(long, value_enum, value_name = "WHEN", global = true, default_value_t = snippet::ColorChoice::Auto)]
    pub color: snippet::ColorChoice,
}

/// `--ext`'s values: every extension name and `all`, listed with a line of help in
/// `--help`. An unknown name is a usage error at parse time, before any work, with the
/// library's message (which lists the names).
#[derive(Debug, Clone, Copy)]
pub struct ExtParser;

/// One line of help per extension, in [`Extension::ALL`]'s order.
fn ext_help(e: vstructc::cond::Extension) -> &'static str {
    use vstructc::cond::Extension as E;
    match e {
        E::ElseIf => "chained `A if C1 else B if C2 else C` statements",
        E::StrictNe => "`p != literal` is `not (p == literal)` in every case",
        E::TokenStrings => "string literals compare with token and asset values by text",
        E::SetTuples => "`set NUMBER` fills every component of a colour, point, vector or normal",
        E::CopyConvert => "`copy` converts int and float and broadcasts a number to a triple",
        E::MultiAlias => "`vstructmemberaliases` is a list of aliases",
        E::ArrayHeads => "heads with several connections feed array members (not implemented yet)",
        E::Nested => "members that are input heads are expanded too (not implemented yet)",
        E::ArrayIndex => "a condition on `name[i]` reads element i of the array `name`",
        E::ArgsChildMeta => "vstruct metadata given as child elements in `.args` files",
    }
}

impl clap::builder::TypedValueParser for ExtParser {
    type Value = String;

    fn parse_ref(
        &self,
        _cmd: &clap::Command,
        _arg: Option<&clap::Arg>,
        value: &std::ffi::OsStr,
    ) -> Result<String, clap::Error> {
        let s = value.to_string_lossy();
        vstructc::cond::Extensions::from_names([s.as_ref()])
            .map(|_| s.to_string())
            .map_err(|e| clap::Error::raw(clap::error::ErrorKind::InvalidValue, format!("{e}\n")))
    }

    fn possible_values(
        &self,
    ) -> Option<Box<dyn Iterator<Item = clap::builder::PossibleValue> + '_>> {
        use clap::builder::PossibleValue;
        let each = vstructc::cond::Extension::ALL
            .into_iter()
            .map(|e| PossibleValue::new(e.name()).help(ext_help(e)));
        Some(Box::new(each.chain(std::iter::once(
            PossibleValue::new("all").help("every extension above"),
        ))))
    }
}

/// `--prefer`'s values, mapped onto the library's [`Prefer`].
fn prefer_parser() -> impl clap::builder::TypedValueParser<Value = Prefer> {
    use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
    PossibleValuesParser::new([
        PossibleValue::new("oso").help("Compiled OSL first (the reference's order)"),
        PossibleValue::new("args").help("`.args` first"),
    ])
    .map(|s| match s.as_str() {
        "args" => Prefer::Args,
        _ => Prefer::Oso,
    })
}

/// How diagnostics are printed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, ValueEnum)]
pub enum DiagFormat {
    /// `severity[CODE]: message`, `  --> file:line:col` and, when the source is at hand,
    /// the offending line with a caret under the column.
    #[default]
    Human,
    /// One JSON object per line.
    Json,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// List the known shaders: kind, format and the file each definition is read from.
    #[command(after_help = EXIT_STATUS)]
    List(list::ListArgs),
    /// Summarise one shader definition.
    #[command(after_help = EXIT_STATUS)]
    Info(info::InfoArgs),
    /// Parse one conditional expression and print its desugared form or diagnostics.
    #[command(after_help = EXIT_STATUS)]
    Expr(expr::ExprArgs),
    /// Expand the vstruct connections of a network (RIB, JSON or USD) and write it back.
    #[command(after_help = EXIT_STATUS)]
    Resolve(resolve::ResolveArgs),
    /// Tell where one input's value comes from (authored, default, written by resolution).
    #[command(after_help = EXIT_STATUS)]
    Explain(explain::ExplainArgs),
    /// Lower each material of a network to the closure IR and print it.
    #[command(after_help = EXIT_STATUS)]
    Compile(compile::CompileArgs),
    /// Render a material-ball preview (PNG or PFM).
    #[command(after_help = EXIT_STATUS)]
    Render(render::RenderArgs),
    /// Evaluate each lobe of a material for one pair of directions.
    #[command(after_help = EXIT_STATUS)]
    Eval(eval::EvalArgs),
}

/// Parse the process arguments and run; the binary's whole `main`.
pub fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            let _ = e.print();
            return if e.use_stderr() {
                ExitCode::from(2)
            } else {
                ExitCode::SUCCESS
            };
        }
    };
    run(cli)
}

/// Run a parsed command line.
pub fn run(cli: Cli) -> ExitCode {
    let common = &cli.common;
    match &cli.command {
        Command::List(a) => list::run(a, common),
        Command::Info(a) => info::run(a, common),
        Command::Expr(a) => expr::run(a, common),
        Command::Resolve(a) => resolve::run(a, common),
        Command::Explain(a) => explain::run(a, common),
        Command::Compile(a) => compile::run(a, common),
        Command::Render(a) => render::run(a, common),
        Command::Eval(a) => eval::run(a, common),
    }
}

/// Print diagnostics to stderr according to the common options and return the exit status
/// they imply: 1 if any error (or any warning under `--deny-warnings`), else 0.
///
/// Volume control: in human output identical diagnostics are printed once
/// ([`Diagnostics::volume_limited`]), diagnostics of the same message shape on different
/// nodes as one that names how many nodes and the first few ([`group`]), at most
/// `--max-diagnostics` of one code (default [`Diagnostics::DEFAULT_MAX_PER_CODE`]) and then
/// one line per code counting the diagnostics left out, and lines are bounded
/// ([`vstructc::diag::Diagnostic::MAX_HUMAN_LINE`]); a located diagnostic shows its source
/// line with a caret ([`snippet::render`]), coloured as `--color` says. JSON output keeps
/// every diagnostic, whole and one per node, unless `--max-diagnostics` is given; its count
/// line is an object `{"code": CODE, "suppressed": N}`. The exit status counts every
/// diagnostic, shown or not. Failures to write to stderr are ignored (there is nowhere left
/// to report them).
pub fn report(diags: &Diagnostics, common: &CommonOptions) -> ExitCode {
    let human = common.diag_format == DiagFormat::Human;
    let keep = |d: &vstructc::Diagnostic| d.severity != Severity::Note || common.verbose;
    let mut err = std::io::BufWriter::new(std::io::stderr().lock());
    let printed = if human {
        let limit = common
            .max_diagnostics
            .unwrap_or(Diagnostics::DEFAULT_MAX_PER_CODE);
        let distinct = diags.volume_limited(0, true, keep);
        let (entries, suppressed) = limit_entries(group::group(&distinct.items), limit);
        print_human(
            &mut err,
            &entries,
            &suppressed,
            common.color.colours_stderr(),
        )
    } else {
        let shown = diags.volume_limited(common.max_diagnostics.unwrap_or(0), false, keep);
        print_json(&mut err, &shown)
    };
    let _ = printed.and_then(|_| err.flush());
    if diags.has_errors() || (common.deny_warnings && diags.has_warnings()) {
        ExitCode::from(1)
    } else {
        ExitCode::SUCCESS
    }
}

/// At most `limit` entries of each code (0: no limit), and per code (in the order the first
/// was left out) how many diagnostics the entries left out stand for.
fn limit_entries(
    entries: Vec<group::Entry<'_>>,
    limit: usize,
) -> (Vec<group::Entry<'_>>, Vec<(&'static str, usize)>) {
    let mut per_code: std::collections::HashMap<&'static str, usize> =
        std::collections::HashMap::new();
    let mut suppressed: Vec<(&'static str, usize)> = Vec::new();
    let mut index: std::collections::HashMap<&'static str, usize> =
        std::collections::HashMap::new();
    let mut shown = Vec::new();
    for e in entries {
        let code = e.first.code.as_str();
        let count = per_code.entry(code).or_insert(0);
        *count += 1;
        if limit == 0 || *count <= limit {
            shown.push(e);
        } else {
            let i = *index.entry(code).or_insert_with(|| {
                suppressed.push((code, 0));
                suppressed.len() - 1
            });
            suppressed[i].1 += e.count();
        }
    }
    (shown, suppressed)
}

fn print_human(
    out: &mut dyn Write,
    entries: &[group::Entry<'_>],
    suppressed: &[(&'static str, usize)],
    colour: bool,
) -> std::io::Result<()> {
    let mut sources = snippet::Sources::default();
    for e in entries {
        writeln!(
            out,
            "{}",
            snippet::render(&e.diagnostic(), &mut sources, colour)
        )?;
    }
    for (code, n) in suppressed {
        writeln!(
            out,
            "note: {n} more {code} diagnostic{} not shown (--max-diagnostics 0 shows all)",
            if *n == 1 { "" } else { "s" }
        )?;
    }
    Ok(())
}

fn print_json(out: &mut dyn Write, shown: &Shown<'_>) -> std::io::Result<()> {
    for d in &shown.items {
        writeln!(out, "{}", d.render_json())?;
    }
    for (code, n) in &shown.suppressed {
        writeln!(out, "{{\"code\":\"{code}\",\"suppressed\":{n}}}")?;
    }
    Ok(())
}
