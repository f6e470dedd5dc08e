//! The protocol loop on standard input and output: a thread reads framed messages (bounded,
//! [`super::transport`]) into a short queue; the main thread answers each message at once and
//! publishes diagnostics only when no message is waiting, so a burst of keystrokes is analysed
//! once, for its last state.

use std::io::Write;
use std::sync::mpsc::{Receiver, sync_channel};

use serde_json::Value;

use super::server::{Flow, Server, log};
use super::transport::{Frame, MAX_CONTENT_LENGTH, read_frame, write_frame};

/// Messages read ahead of the one being handled (a bound on what a fast client can queue).
const QUEUE: usize = 16;

/// What the reader thread passes on.
enum Input {
    Frame(Frame),
    /// The input cannot be read as messages any more.
    Failed(String),
}

/// Serves LSP on standard input and output until `exit`; returns the process's exit status (0
/// after `shutdown` then `exit`, 1 otherwise).
pub fn serve_stdio() -> i32 {
    let (tx, rx) = sync_channel::<Input>(QUEUE);
    let reader = std::thread::Builder::new()
        .name("lsp-reader".into())
        .spawn(move || {
            let stdin = std::io::stdin();
            let mut input = stdin.lock();
            loop {
                let (next, last) = match read_frame(&mut input) {
                    Ok(Frame::End) => return,
                    Ok(frame) => (Input::Frame(frame), false),
                    Err(e) => (Input::Failed(e.to_string()), true),
                };
                if tx.send(next).is_err() || last {
                    return;
                }
            }
        });
    if let Err(e) = reader {
        log(&format!("cannot start the reader thread: {e}"));
        return 1;
    }
    let stdout = std::io::stdout();
    serve(&rx, &mut stdout.lock())
}

/// The loop: messages from `rx`, replies to `output`.
fn serve(rx: &Receiver<Input>, output: &mut impl Write) -> i32 {
    let mut server = Server::new();
    let mut out: Vec<Value> = Vec::new();
    loop {
        let Ok(first) = rx.recv() else {
            log("the input ended without `exit`");
            return 1;
        };
        let mut next = Some(first);
        while let Some(input) = next {
            let flow = match input {
                Input::Frame(Frame::Body(body)) => server.handle(&body, &mut out),
                Input::Frame(Frame::TooLarge(n)) => {
                    log(&format!(
                        "a message of {n} bytes skipped: at most {MAX_CONTENT_LENGTH} are read"
                    ));
                    Flow::Continue
                }
                Input::Frame(Frame::End) => Flow::Exit(1),
                Input::Failed(e) => {
                    log(&format!("{e}; stopping"));
                    Flow::Exit(1)
                }
            };
            if !send(output, &mut out) {
                return 1;
            }
            if let Flow::Exit(status) = flow {
                return status;
            }
            next = rx.try_recv().ok();
        }
        server.publish(&mut out);
        if !send(output, &mut out) {
            return 1;
        }
    }
}

/// Writes and clears `out`; `false` if the output is closed.
fn send(output: &mut impl Write, out: &mut Vec<Value>) -> bool {
    for message in out.drain(..) {
        if let Err(e) = write_frame(output, &message) {
            log(&format!("cannot write to the client: {e}"));
            return false;
        }
    }
    true
}
