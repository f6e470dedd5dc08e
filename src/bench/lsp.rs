//! `rondo bench lsp`: how long the language server takes to answer an editor on a generated
//! scene of n spheres (`flat` of [`super::load`]): diagnostics after one keystroke, after a typo,
//! and a completion of material names. The server is driven in process, message by message, as
//! its protocol loop drives it ([`crate::lsp::server::Server`]); pipe transfer is not counted.
//!
//! Each keystroke is a one-character incremental change in a different entity (a digit added to
//! or removed from a radius), followed by the diagnostics the loop publishes when no message is
//! waiting: the figure is the time from the change arriving to its diagnostics being ready.

use std::path::Path;
use std::time::{Duration, Instant};

use cpu_time::ProcessTime;
use serde_json::{Value, json};

use crate::lsp::server::Server;

/// Times of one run, in milliseconds: wall clock and CPU time of the process.
#[derive(Clone, Debug, Default)]
pub struct Timings {
    /// Opening the document: the first full load and check.
    pub open: (f64, f64),
    /// Each keystroke to its diagnostics.
    pub keystroke: Vec<(f64, f64)>,
    /// Each typo (a material name cut short) to its error diagnostic.
    pub typo: Vec<(f64, f64)>,
    /// Each completion of an empty material string.
    pub completion: Vec<(f64, f64)>,
}

/// Runs the benchmark on a scene of `entities` spheres written into `dir`, `edits` times each.
pub fn run(entities: usize, edits: usize, dir: &Path) -> Result<Timings, String> {
    let path = super::load::generate("flat", entities, dir)?;
    let path = std::path::absolute(&path).map_err(|e| e.to_string())?;
    let mut text =
        std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let uri = crate::lsp::uri::from_path(&path);
    let mut server = Server::new();
    let mut out = Vec::new();
    let send = |server: &mut Server, out: &mut Vec<Value>, message: Value| {
        let body = serde_json::to_vec(&message).map_err(|e| e.to_string())?;
        server.handle(&body, out);
        Ok::<(), String>(())
    };
    send(
        &mut server,
        &mut out,
        json!({"jsonrpc": "2.0", "id": 0, "method": "initialize", "params": {"capabilities": {}}}),
    )?;
    let mut t = Timings::default();
    let open = json!({"jsonrpc": "2.0", "method": "textDocument/didOpen", "params": {"textDocument": {"uri": uri, "languageId": "ron", "version": 1, "text": text}}});
    t.open = timed(|| {
        send(&mut server, &mut out, open)?;
        server.publish(&mut out);
        Ok(())
    })?;
    let mut version = 1;
    // Replaces bytes `at..at + len` of the text with `new`, as an incremental change, and
    // returns the error count of the diagnostics that follow.
    let mut edit = |server: &mut Server, text: &mut String, at: usize, len: usize, new: &str| {
        version += 1;
        let (start, end) = (position(text, at), position(text, at + len));
        text.replace_range(at..at + len, new);
        let change = json!({"jsonrpc": "2.0", "method": "textDocument/didChange", "params": {
            "textDocument": {"uri": uri, "version": version},
            "contentChanges": [{"range": {"start": start, "end": end}, "text": new}]}});
        let mut out = Vec::new();
        send(server, &mut out, change)?;
        server.publish(&mut out);
        Ok::<usize, String>(errors(&out))
    };
    for k in 0..edits {
        let e = ((k * 7919 + 1) % entities.max(1)).max(1);
        let radius = entity_field(&text, e, "radius: 0.4")? + "radius: 0.4".len();
        let ((), times) = timed_value(|| {
            let errors = edit(&mut server, &mut text, radius, 0, "1")?;
            if errors > 0 {
                return Err(format!("a keystroke gave {errors} errors"));
            }
            Ok(())
        })?;
        t.keystroke.push(times);
        edit(&mut server, &mut text, radius, 1, "")?;
    }
    for k in 0..edits {
        let e = ((k * 7919 + 2) % entities.max(1)).max(1);
        let clay = entity_field(&text, e, "\"clay\"")?;
        let ((), times) = timed_value(|| {
            let errors = edit(&mut server, &mut text, clay + 4, 1, "")?;
            if errors != 1 {
                return Err(format!("a typo gave {errors} errors, not 1"));
            }
            Ok(())
        })?;
        t.typo.push(times);
        edit(&mut server, &mut text, clay + 4, 0, "y")?;
    }
    let clay = entity_field(&text, (entities / 2).max(1), "\"clay\"")?;
    edit(&mut server, &mut text, clay + 1, 4, "")?;
    let inside = position(&text, clay + 1);
    for id in 0..edits {
        let request = json!({"jsonrpc": "2.0", "id": id + 1, "method": "textDocument/completion",
            "params": {"textDocument": {"uri": uri}, "position": inside}});
        let (items, times) = timed_value(|| {
            let mut out = Vec::new();
            send(&mut server, &mut out, request)?;
            Ok(out
                .first()
                .and_then(|r| r["result"].as_array())
                .map_or(0, Vec::len))
        })?;
        if items != 2 {
            return Err(format!("completion gave {items} names, not the 2 defined"));
        }
        t.completion.push(times);
    }
    Ok(t)
}

/// The offset of `field` in entity `e` (`Entity(name: "e{e}"`) of a generated scene.
fn entity_field(text: &str, e: usize, field: &str) -> Result<usize, String> {
    let start = text
        .find(&format!("Entity(name: \"e{e}\""))
        .ok_or_else(|| format!("entity e{e} not found"))?;
    let end = text[start..].find('\n').map_or(text.len(), |n| start + n);
    text[start..end]
        .find(field)
        .map(|i| start + i)
        .ok_or_else(|| format!("{field} not found in entity e{e}"))
}

/// The LSP position of byte `offset` of ASCII `text`.
fn position(text: &str, offset: usize) -> Value {
    let before = &text[..offset];
    let line = before.matches('\n').count();
    let col = before.rsplit('\n').next().map_or(0, str::len);
    json!({"line": line, "character": col})
}

/// The number of error diagnostics in the messages `out`.
fn errors(out: &[Value]) -> usize {
    out.iter()
        .filter(|m| m["method"] == "textDocument/publishDiagnostics")
        .flat_map(|m| {
            m["params"]["diagnostics"]
                .as_array()
                .cloned()
                .unwrap_or_default()
        })
        .filter(|d| d["severity"] == 1)
        .count()
}

fn timed(f: impl FnOnce() -> Result<(), String>) -> Result<(f64, f64), String> {
    timed_value(f).map(|((), t)| t)
}

/// `f`'s value, with its wall-clock and CPU times in milliseconds.
fn timed_value<T>(f: impl FnOnce() -> Result<T, String>) -> Result<(T, (f64, f64)), String> {
    let (wall, cpu) = (Instant::now(), ProcessTime::now());
    let value = f()?;
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    Ok((value, (ms(wall.elapsed()), ms(cpu.elapsed()))))
}

/// `| what | median wall | max wall | median CPU | max CPU |` rows of a Markdown table.
pub fn markdown(entities: usize, t: &Timings) -> String {
    let mut s = format!(
        "`rondo bench lsp --entities {entities}`\n\n| step | runs | median ms (wall) | max ms (wall) | median ms (CPU) | max ms (CPU) |\n|---|---:|---:|---:|---:|---:|\n"
    );
    let mut row = |what: &str, v: &[(f64, f64)]| {
        let stat = |pick: fn(&(f64, f64)) -> f64| {
            let mut x: Vec<f64> = v.iter().map(pick).collect();
            x.sort_by(f64::total_cmp);
            (
                x.get(x.len() / 2).copied().unwrap_or(f64::NAN),
                x.last().copied().unwrap_or(f64::NAN),
            )
        };
        let ((wm, wx), (cm, cx)) = (stat(|p| p.0), stat(|p| p.1));
        s.push_str(&format!(
            "| {what} | {} | {wm:.1} | {wx:.1} | {cm:.1} | {cx:.1} |\n",
            v.len()
        ));
    };
    row("open (first load + check)", &[t.open]);
    row("keystroke → diagnostics", &t.keystroke);
    row("typo → error diagnostic", &t.typo);
    row("completion of material names", &t.completion);
    s
}
