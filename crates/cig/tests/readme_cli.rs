//! README's "Using it" block against the real command line: every `cig` line shown there must
//! name subcommands that exist, flags each subcommand's `--help` lists, and arguments clap
//! parses (unknown flags, extra positional arguments and values of the wrong type fail; with
//! `--help` last, clap does not check required arguments or conflicts between flags); the lines
//! that need no database, network or GPU are run for real. A renamed flag fails this suite
//! instead of the reader.
//!
//! How a README line becomes commands: continuation lines (ending in `\`, or indented under a
//! `cig` line) are joined; `# comments` and `> FILE` redirections are dropped; an optional part
//! opening inside a value (`36.12,-120.98[,HEAT_MW[,SECONDS]]`) is dropped, and `...` with it;
//! every bracketed group of arguments (`[--visibility 40000]`) is kept as plain arguments, and a
//! group of alternatives (`[--rain MM_PER_H | --snow MM_PER_H]`) gives one command per
//! alternative.

mod common;

use common::cig;
use std::collections::HashMap;
use std::time::Duration;

/// README's text.
fn readme() -> String {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../README.md");
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// The body of the first ```sh block under the "## Using it" heading.
fn using_it_block(readme: &str) -> String {
    let mut lines = readme.lines();
    assert!(
        lines.by_ref().any(|l| l.trim_end() == "## Using it"),
        "README has no \"## Using it\" heading"
    );
    for line in lines.by_ref() {
        if line.starts_with("## ") {
            panic!("README's \"## Using it\" section has no ```sh block");
        }
        if line.trim_end() == "```sh" {
            break;
        }
    }
    let mut body = String::new();
    for line in lines {
        if line.trim_end() == "```" {
            return body;
        }
        body.push_str(line);
        body.push('\n');
    }
    panic!("README's \"Using it\" ```sh block is not closed");
}

/// The line without its shell comment (a `#` at the start or after white space).
fn strip_comment(line: &str) -> &str {
    let mut previous = ' ';
    for (i, c) in line.char_indices() {
        if c == '#' && previous.is_whitespace() {
            return &line[..i];
        }
        previous = c;
    }
    line
}

/// Each `cig` command line of a block, continuations joined, comments stripped. Any other
/// non-blank line is an error: the block is expected to hold `cig` commands only.
fn command_lines(block: &str) -> Vec<String> {
    let mut commands: Vec<String> = Vec::new();
    let mut continued = false;
    for raw in block.lines() {
        let text = strip_comment(raw).trim();
        let (text, continues) = match text.strip_suffix('\\') {
            Some(rest) => (rest.trim_end(), true),
            None => (text, false),
        };
        let indented = raw.starts_with(char::is_whitespace);
        if text.is_empty() {
            assert!(
                !continued || raw.trim().starts_with('#'),
                "a continued line ends in a blank line"
            );
        } else if (continued || indented) && !commands.is_empty() {
            let last = commands.last_mut().expect("a command");
            last.push(' ');
            last.push_str(text);
        } else if text.starts_with("cig ") && !continued {
            commands.push(text.to_string());
        } else {
            panic!("README's Using it block: neither a cig command nor its continuation: {raw:?}");
        }
        continued = continues;
    }
    commands
}

/// Drops optional parts that open inside a word (`36.12,-120.98[,HEAT_MW]` becomes
/// `36.12,-120.98`): only brackets that open a word are argument groups.
fn drop_optional_value_parts(line: &str) -> String {
    let mut out = String::new();
    let mut depth = 0usize;
    let mut previous = ' ';
    for c in line.chars() {
        if depth > 0 {
            match c {
                '[' => depth += 1,
                ']' => depth -= 1,
                _ => {}
            }
        } else if c == '[' && !previous.is_whitespace() && previous != '[' {
            depth = 1;
        } else {
            out.push(c);
        }
        previous = c;
    }
    assert_eq!(depth, 0, "unbalanced brackets in {line:?}");
    out
}

/// A word of a command line, or a bracketed group of alternatives.
#[derive(Debug)]
enum Item {
    Word(String),
    Group(Vec<Vec<Item>>),
}

/// Parses items up to the end or the closing bracket, split at `|` into alternatives.
fn parse_items(tokens: &[String], pos: &mut usize, in_group: bool) -> Vec<Vec<Item>> {
    let mut alternatives = vec![Vec::new()];
    while let Some(token) = tokens.get(*pos) {
        *pos += 1;
        match token.as_str() {
            "[" => {
                let group = parse_items(tokens, pos, true);
                alternatives
                    .last_mut()
                    .expect("one")
                    .push(Item::Group(group));
            }
            "]" => {
                assert!(in_group, "a ']' without its '['");
                return alternatives;
            }
            "|" => alternatives.push(Vec::new()),
            "..." => {}
            ">" => *pos += 1, // a redirection and its file
            _ => alternatives
                .last_mut()
                .expect("one")
                .push(Item::Word(token.clone())),
        }
    }
    assert!(!in_group, "a '[' without its ']'");
    alternatives
}

/// Every command a sequence of items stands for (one per choice of alternatives).
fn expand(items: &[Item]) -> Vec<Vec<String>> {
    let mut out = vec![Vec::new()];
    for item in items {
        out = match item {
            Item::Word(w) => out
                .into_iter()
                .map(|mut c| {
                    c.push(w.clone());
                    c
                })
                .collect(),
            Item::Group(alternatives) => {
                let tails: Vec<Vec<String>> = alternatives.iter().flat_map(|a| expand(a)).collect();
                out.iter()
                    .flat_map(|head| {
                        tails.iter().map(move |tail| {
                            let mut c = head.clone();
                            c.extend(tail.iter().cloned());
                            c
                        })
                    })
                    .collect()
            }
        };
    }
    out
}

/// The argument lists (after `cig`) a README command line stands for.
fn variants(line: &str) -> Vec<Vec<String>> {
    let plain = drop_optional_value_parts(line)
        .replace('[', " [ ")
        .replace(']', " ] ");
    let tokens: Vec<String> = plain.split_whitespace().map(str::to_string).collect();
    assert_eq!(tokens.first().map(String::as_str), Some("cig"), "{line}");
    let alternatives = parse_items(&tokens[1..], &mut 0, false);
    assert_eq!(alternatives.len(), 1, "a '|' outside brackets in {line:?}");
    expand(&alternatives[0])
}

/// An option word (`--alt`, `-v`), without an attached `=value`; not a negative number.
fn option_name(word: &str) -> Option<&str> {
    let name = word.split('=').next().unwrap_or(word);
    let long = name.strip_prefix("--").is_some_and(|r| !r.is_empty());
    let short = name.len() == 2
        && name.starts_with('-')
        && name.chars().nth(1).is_some_and(|c| c.is_ascii_alphabetic());
    (long || short).then_some(name)
}

/// Whether `--help` text lists the option (as a whole word: `--frame` is not `--frames`).
fn help_lists(help: &str, option: &str) -> bool {
    help.match_indices(option).any(|(i, _)| {
        let before = help[..i].chars().next_back();
        let after = help[i + option.len()..].chars().next();
        before.is_none_or(|c| c.is_whitespace() || c == ',' || c == '[')
            && after.is_none_or(|c| !(c.is_ascii_alphanumeric() || c == '-' || c == '_'))
    })
}

/// The options of `words` that `help` does not list.
fn missing_options(help: &str, words: &[String]) -> Vec<String> {
    let mut missing: Vec<String> = words
        .iter()
        .filter_map(|w| option_name(w))
        .filter(|o| !help_lists(help, o))
        .map(str::to_string)
        .collect();
    missing.dedup();
    missing
}

/// The subcommand names of a `--help` text's "Commands:" section.
fn subcommands(help: &str) -> Vec<String> {
    help.lines()
        .skip_while(|l| l.trim_end() != "Commands:")
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next())
        .map(str::to_string)
        .collect()
}

/// `cig PATH... --help`, which must succeed; kept per path.
struct Helps(HashMap<Vec<String>, String>);

impl Helps {
    fn new() -> Self {
        Helps(HashMap::new())
    }

    fn of(&mut self, path: &[String]) -> String {
        if let Some(h) = self.0.get(path) {
            return h.clone();
        }
        let out = cig()
            .args(path)
            .arg("--help")
            .timeout(Duration::from_secs(30))
            .output()
            .expect("run cig");
        assert!(
            out.status.success(),
            "`cig {} --help` failed: {}",
            path.join(" "),
            String::from_utf8_lossy(&out.stderr)
        );
        let help = String::from_utf8_lossy(&out.stdout).to_string();
        self.0.insert(path.to_vec(), help.clone());
        help
    }

    /// The leading words of `args` that name subcommands (`db synth`, `config default`).
    fn command_path(&mut self, args: &[String]) -> Vec<String> {
        let mut path = Vec::new();
        for word in args {
            if !subcommands(&self.of(&path)).contains(word) {
                break;
            }
            path.push(word.clone());
        }
        path
    }
}

/// A placeholder word of the README (`DB`, `N`, `EV`, `TOP_M,VIS_M`).
fn is_placeholder(word: &str) -> bool {
    word.chars().any(|c| c.is_ascii_uppercase())
        && word
            .chars()
            .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || "_,:".contains(c))
}

/// Has clap parse the whole argument list by putting `--help` after it: clap stops at the
/// first word it cannot take (an unknown option, one positional too many, a value of the wrong
/// type) before it prints the help, and reads nothing else. A placeholder the value's type
/// refuses (`--count N`) is tried as `1`. `Err` holds clap's complaint.
fn parses(args: &[String]) -> Result<(), String> {
    let mut args = args.to_vec();
    for _ in 0..=args.len() {
        let out = cig()
            .args(&args)
            .arg("--help")
            .timeout(Duration::from_secs(30))
            .output()
            .expect("run cig");
        if out.status.success() {
            return Ok(());
        }
        let stderr = String::from_utf8_lossy(&out.stderr).to_string();
        let refused = stderr
            .split_once("invalid value '")
            .and_then(|(_, rest)| rest.split_once('\''))
            .map(|(value, _)| value.to_string());
        match refused {
            Some(v) if is_placeholder(&v) => {
                let i = args.iter().position(|a| *a == v).expect("the refused word");
                args[i] = "1".to_string();
            }
            _ => {
                let reason: Vec<&str> =
                    stderr.lines().filter(|l| l.starts_with("error:")).collect();
                return Err(if reason.is_empty() {
                    stderr
                } else {
                    reason.join("\n")
                });
            }
        }
    }
    Err(format!("placeholders kept being refused in {args:?}"))
}

/// Every argument list the README's Using it block stands for, with its README line.
fn readme_commands() -> Vec<(String, Vec<Vec<String>>)> {
    command_lines(&using_it_block(&readme()))
        .into_iter()
        .map(|line| {
            let v = variants(&line);
            (line, v)
        })
        .collect()
}

#[test]
fn every_readme_command_exists_with_its_flags_and_arguments() {
    let commands = readme_commands();
    assert!(commands.len() >= 15, "{} command lines", commands.len());
    let mut helps = Helps::new();
    let mut failures = Vec::new();
    for (line, variants) in &commands {
        for args in variants {
            let path = helps.command_path(args);
            if path.is_empty() {
                failures.push(format!("{line}\n    names no cig subcommand"));
                continue;
            }
            let help = helps.of(&path);
            if !subcommands(&help).is_empty() {
                failures.push(format!(
                    "{line}\n    `cig {}` needs a subcommand",
                    path.join(" ")
                ));
                continue;
            }
            let missing = missing_options(&help, &args[path.len()..]);
            if !missing.is_empty() {
                failures.push(format!(
                    "{line}\n    `cig {} --help` does not list {}",
                    path.join(" "),
                    missing.join(", ")
                ));
            }
            if let Err(e) = parses(args) {
                failures.push(format!(
                    "{line}\n    cig {}\n    {}",
                    args.join(" "),
                    e.trim()
                ));
            }
        }
    }
    let mut unique: Vec<String> = Vec::new();
    for f in failures {
        if !unique.contains(&f) {
            unique.push(f);
        }
    }
    assert!(
        unique.is_empty(),
        "README's Using it block disagrees with the command line:\n{}",
        unique.join("\n")
    );
}

/// The README commands that need no database, network, window or GPU, run as written.
#[test]
fn readme_commands_that_need_nothing_run() {
    let dir = tempfile::tempdir().expect("temporary directory");
    let mut ran: Vec<String> = Vec::new();
    for (line, variants) in readme_commands() {
        for args in variants {
            let words: Vec<&str> = args.iter().map(String::as_str).collect();
            match words.as_slice() {
                ["ephem", ..] | ["plume", ..] | ["lod", ..] => {
                    let out = cig()
                        .args(&args)
                        .current_dir(dir.path())
                        .timeout(Duration::from_secs(60))
                        .assert()
                        .success();
                    let stdout = &out.get_output().stdout;
                    if args.iter().any(|a| a == "--json") {
                        serde_json::from_slice::<serde_json::Value>(stdout).unwrap_or_else(|e| {
                            panic!("{line}: {e}: {}", String::from_utf8_lossy(stdout))
                        });
                    }
                }
                ["config", "default"] => {
                    // "pass with --config cig.toml": what it prints is a configuration cig reads.
                    let out = cig()
                        .args(&args)
                        .timeout(Duration::from_secs(60))
                        .assert()
                        .success();
                    let toml = dir.path().join("cig.toml");
                    std::fs::write(&toml, &out.get_output().stdout).expect("write cig.toml");
                    cig()
                        .arg("--config")
                        .arg(&toml)
                        .args(["config", "default"])
                        .timeout(Duration::from_secs(60))
                        .assert()
                        .success();
                }
                _ => continue,
            }
            ran.push(args.join(" "));
        }
    }
    for expected in ["ephem", "plume", "config default"] {
        assert!(
            ran.iter().any(|r| r.starts_with(expected)),
            "README's Using it block shows no `cig {expected}` to run (ran: {ran:?})"
        );
    }
}

#[test]
fn the_extractor_joins_continuations_and_expands_brackets() {
    let block = "\
cig db info   DB --json [--lod-errors]   # a comment with --not-a-flag
cig render --db DB \\
           [--smoke 36.12,-120.98[,HEAT_MW[,SECONDS]] ...] [--wind 5,270]   # fires
           [--rain MM_PER_H | --snow MM_PER_H] [--sky physical|flat]
cig config default > cig.toml      # pass with --config cig.toml
";
    let lines = command_lines(block);
    assert_eq!(lines.len(), 3, "{lines:?}");
    let words = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    assert_eq!(
        variants(&lines[0]),
        [words(&["db", "info", "DB", "--json", "--lod-errors"])]
    );
    let render = variants(&lines[1]);
    let common = [
        "render",
        "--db",
        "DB",
        "--smoke",
        "36.12,-120.98",
        "--wind",
        "5,270",
    ];
    let with = |extra: &[&str]| {
        let mut w = words(&common);
        w.extend(words(extra));
        w
    };
    assert_eq!(
        render,
        [
            with(&["--rain", "MM_PER_H", "--sky", "physical|flat"]),
            with(&["--snow", "MM_PER_H", "--sky", "physical|flat"]),
        ]
    );
    assert_eq!(variants(&lines[2]), [words(&["config", "default"])]);
}

#[test]
fn the_checker_reports_a_wrong_flag() {
    let commands = readme_commands();
    assert!(
        commands.len() >= 15,
        "the extractor found {} command lines in README's Using it block",
        commands.len()
    );
    let help = Helps::new().of(&["ephem".to_string()]);
    let words = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    assert_eq!(
        missing_options(
            &help,
            &words(&["--lat", "48.8", "--no-such-flag", "--lon", "-2.35"])
        ),
        ["--no-such-flag"]
    );
    // A flag's prefix is not the flag.
    assert_eq!(missing_options(&help, &words(&["--ti"])), ["--ti"]);
    assert!(missing_options(&help, &words(&["--time", "--json", "-v"])).is_empty());
    // clap refuses what the help check cannot see: an unknown flag, a positional too many.
    assert!(parses(&words(&["ephem", "--lat", "1", "--no-such-flag"])).is_err());
    assert!(parses(&words(&["query", "hat", "DB", "36.1", "-121.0", "7"])).is_err());
    assert!(parses(&words(&["query", "hat", "DB", "36.1", "-121.0"])).is_ok());
    assert!(parses(&words(&["dis", "listen", "--port", "3000", "--count", "N"])).is_ok());
}
