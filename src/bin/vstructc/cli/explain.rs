//! `vstructc explain HANDLE.INPUT INPUT`: the story of one member input's value.

use super::CommonOptions;
use super::input::{ReadInput, print_stdout, read};
use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;
use vstructc::network::Network;
use vstructc::resolve::{MemberEvent, Outcome, ReadSource, resolve};

/// Arguments of `vstructc explain`.
#[derive(Debug, clap::Args)]
pub struct ExplainArgs {
    /// The member input to explain, as `HANDLE.INPUT` (the handle may contain dots; the
    /// input is the text after the last dot).
    pub target: String,
    /// The network: a RIB or JSON file, or `-` for standard input.
    pub input: PathBuf,
    /// Explain as if `--no-conditions` were given.
    #[arg(long)]
    pub no_conditions: bool,
}

/// Run `vstructc explain`.
pub fn run(args: &ExplainArgs, common: &CommonOptions) -> ExitCode {
    let Some((handle, input)) = args.target.rsplit_once('.') else {
        eprintln_quiet!("error: expected HANDLE.INPUT, got `{}`", args.target);
        return ExitCode::from(2);
    };
    let ReadInput {
        mut options,
        registry,
        name,
        mut network,
    } = match read(&args.input, args.no_conditions, common) {
        Ok(p) => p,
        Err(status) => return status,
    };
    options.record_events = true;
    let Some(node) = network.find(handle) else {
        eprintln_quiet!("error: no node `{handle}` in {}", name);
        return ExitCode::from(2);
    };
    let res = resolve(&mut network, &registry, &options);
    let events: Vec<&MemberEvent> = res
        .events
        .iter()
        .filter(|e| e.node == node && e.member == input)
        .collect();
    let text = if events.is_empty() {
        format!(
            "{handle}.{input} was not expanded from any vstruct connection: it is not a member \
             of a connected input head of `{}`.\n",
            network[node].shader()
        )
    } else {
        events.iter().map(|e| render_event(&network, e)).collect()
    };
    match print_stdout(&text, common) {
        Ok(()) => ExitCode::SUCCESS,
        Err(failed) => failed,
    }
}

/// The story of one member decision, as readable text.
pub fn render_event(net: &Network, e: &MemberEvent) -> String {
    let name = |n| net[n].display_name();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{}.{}: member of head `{}`, connected to {}.{}",
        name(e.node),
        e.member,
        e.head,
        name(e.upstream),
        e.upstream_head
    );
    match &e.matched {
        Some((output, by)) => {
            let _ = writeln!(
                s,
                "  matches upstream member output `{output}` (by name `{by}`)"
            );
        }
        None if e.outcome == Outcome::DirectConnectionWins => {}
        None => {
            let _ = writeln!(s, "  no upstream member has any of its names");
        }
    }
    if let Some(expr) = &e.expression {
        let _ = writeln!(s, "  conditional: {expr}");
        for r in &e.reads {
            let value = match &r.source {
                ReadSource::Authored(v) => format!("authored {v}"),
                ReadSource::Default(v) => format!("default {v}"),
                ReadSource::NoValue => "declared, no value".to_string(),
                ReadSource::Undeclared => "not an input of the upstream type".to_string(),
            };
            let conn = if r.connected { ", connected" } else { "" };
            let _ = writeln!(
                s,
                "    reads {}.{} = {value}{conn}",
                name(e.upstream),
                r.param
            );
        }
        if let Some(a) = &e.action {
            let _ = writeln!(s, "  chosen action: {a}");
        }
    }
    let outcome = match &e.outcome {
        Outcome::Connected => format!(
            "connected to {}.{}",
            name(e.upstream),
            e.matched.as_ref().map(|m| m.0.as_str()).unwrap_or("?")
        ),
        Outcome::Ignored => "ignored: keeps its authored value or default".to_string(),
        Outcome::Written(v) => format!("value {v} written"),
        Outcome::NotApplied(why) => format!("unchanged: {why}"),
        Outcome::DirectConnectionWins => {
            "unchanged: already connected, the direct connection wins".to_string()
        }
        Outcome::Unparsable => "never connected: its conditional does not parse".to_string(),
        Outcome::NoCounterpart => "untouched".to_string(),
    };
    let _ = writeln!(s, "  result: {outcome}");
    s
}
