//! The server's state and its dispatch of JSON-RPC messages (LSP 3.17): the lifecycle
//! (`initialize`, `shutdown`, `exit`), document sync, and the requests it answers.
//!
//! Any message body goes in ([`Server::handle`]); what to send comes out as JSON values. Bad
//! input gets the JSON-RPC error it calls for (not JSON: -32700 with a null id; not a request:
//! -32600; an unknown method: -32601; parameters of the wrong shape: -32602; a request before
//! `initialize`: -32002) and the server goes on.

use std::collections::{BTreeSet, HashMap};
use std::path::PathBuf;
use std::sync::Arc;

use lsp_types::{
    CompletionOptions, CompletionParams, CompletionResponse, DidChangeTextDocumentParams,
    DidCloseTextDocumentParams, DidOpenTextDocumentParams, DocumentSymbolParams,
    DocumentSymbolResponse, GotoDefinitionParams, GotoDefinitionResponse, HoverParams,
    HoverProviderCapability, InitializeResult, OneOf, PublishDiagnosticsParams, SaveOptions,
    ServerCapabilities, ServerInfo, TextDocumentPositionParams, TextDocumentSyncCapability,
    TextDocumentSyncKind, TextDocumentSyncOptions, TextDocumentSyncSaveOptions,
};
use serde::de::DeserializeOwned;
use serde_json::{Value, json};

use super::completion::completion;
use super::definition::definition;
use super::diagnostics::{Analysis, Finding};
use super::documents::{Document, Documents};
use super::hover::hover;
use super::outline::{Outline, outline, top_name};
use super::symbols::symbols;
use super::uri::to_path;

/// JSON-RPC's and LSP's error codes.
pub mod code {
    /// The body is not JSON.
    pub const PARSE_ERROR: i64 = -32700;
    /// JSON that is not a request or a notification.
    pub const INVALID_REQUEST: i64 = -32600;
    /// No such method.
    pub const METHOD_NOT_FOUND: i64 = -32601;
    /// Parameters of the wrong shape.
    pub const INVALID_PARAMS: i64 = -32602;
    /// A request before `initialize`.
    pub const SERVER_NOT_INITIALIZED: i64 = -32002;
}

/// Whether the server goes on after a message.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Flow {
    /// Read the next message.
    Continue,
    /// `exit` was received: end the process with this status (0 after `shutdown`, else 1).
    Exit(i32),
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum State {
    Uninitialized,
    Running,
    ShutDown,
}

/// A request's failure: a JSON-RPC error code and message.
type Failure = (i64, String);

/// The language server.
pub struct Server {
    state: State,
    documents: Documents,
    analyses: HashMap<String, Analysis>,
    outlines: HashMap<String, Outline>,
    /// Documents whose diagnostics are out of date.
    dirty: BTreeSet<String>,
    /// The open prefab buffers' texts by their files' canonical paths: every scene's load
    /// reads them instead of the files.
    overlays: HashMap<PathBuf, Arc<str>>,
    /// A prefab buffer was closed: the scenes' loads read its file from disk again.
    prefab_closed: bool,
    /// A scene buffer was closed: what its loads found in prefabs goes from their buffers.
    scene_closed: bool,
}

impl Default for Server {
    fn default() -> Self {
        Self::new()
    }
}

impl Server {
    /// A server waiting for `initialize`.
    pub fn new() -> Self {
        Self {
            state: State::Uninitialized,
            documents: Documents::default(),
            analyses: HashMap::new(),
            outlines: HashMap::new(),
            dirty: BTreeSet::new(),
            overlays: HashMap::new(),
            prefab_closed: false,
            scene_closed: false,
        }
    }

    /// Handles one message `body`, pushing the messages to send to `out`.
    pub fn handle(&mut self, body: &[u8], out: &mut Vec<Value>) -> Flow {
        let message: Value = match serde_json::from_slice(body) {
            Ok(m) => m,
            Err(e) => {
                out.push(error(
                    Value::Null,
                    code::PARSE_ERROR,
                    format!("not JSON: {e}"),
                ));
                return Flow::Continue;
            }
        };
        let Some(object) = message.as_object() else {
            out.push(error(
                Value::Null,
                code::INVALID_REQUEST,
                "not a JSON object".into(),
            ));
            return Flow::Continue;
        };
        let params = object.get("params").cloned().unwrap_or(Value::Null);
        let id = object.get("id").cloned();
        match (object.get("method").and_then(Value::as_str), id) {
            (Some(method), Some(id @ (Value::Number(_) | Value::String(_)))) => {
                let reply = self.request(method, params);
                out.push(match reply {
                    Ok(result) => json!({"jsonrpc": "2.0", "id": id, "result": result}),
                    Err((c, message)) => error(id, c, message),
                });
                Flow::Continue
            }
            (Some(method), None) => self.notification(method, params, out),
            // A response to a request of ours (the server sends none): nothing to do.
            (None, Some(_)) if object.contains_key("result") || object.contains_key("error") => {
                Flow::Continue
            }
            (_, id) => {
                let id = id
                    .filter(|i| i.is_number() || i.is_string())
                    .unwrap_or(Value::Null);
                out.push(error(
                    id,
                    code::INVALID_REQUEST,
                    "not a request: needs a string `method` and a number or string `id`".into(),
                ));
                Flow::Continue
            }
        }
    }

    /// Publishes the diagnostics of every document changed since the last call, to `out`.
    ///
    /// Open prefab buffers stand for their files in every scene's load: when one changed (or
    /// was closed), every open scene is analysed again, and every open prefab buffer gets what
    /// those loads found in it.
    pub fn publish(&mut self, out: &mut Vec<Value>) {
        let dirty = std::mem::take(&mut self.dirty);
        let prefab_changed = std::mem::take(&mut self.prefab_closed)
            || dirty
                .iter()
                .any(|uri| self.documents.get(uri).is_some_and(is_prefab));
        let (mut scenes, mut prefabs) = (BTreeSet::new(), BTreeSet::new());
        for uri in self.documents.uris() {
            let Some(doc) = self.documents.get(uri) else {
                continue;
            };
            match is_prefab(doc) {
                true if prefab_changed || dirty.contains(uri) => prefabs.insert(uri.clone()),
                false if prefab_changed || dirty.contains(uri) => scenes.insert(uri.clone()),
                _ => false,
            };
        }
        if prefab_changed {
            self.overlays = self.prefab_overlays();
        }
        for uri in &scenes {
            let Some(doc) = self.documents.get(uri) else {
                continue;
            };
            let Some(path) = doc.path.clone() else {
                continue;
            };
            let analysis = self.analyses.entry(uri.clone()).or_insert_with(|| {
                let mut a = Analysis::default();
                a.set_overlays(self.overlays.clone());
                a
            });
            if prefab_changed {
                analysis.set_overlays(self.overlays.clone());
            }
            let diagnostics = analysis.diagnose(doc, &path);
            out.push(publication(uri, doc, diagnostics));
        }
        if !scenes.is_empty() || std::mem::take(&mut self.scene_closed) {
            prefabs.extend(
                self.documents
                    .uris()
                    .filter(|u| self.documents.get(u).is_some_and(is_prefab))
                    .cloned(),
            );
        }
        for uri in &prefabs {
            let Some(doc) = self.documents.get(uri) else {
                continue;
            };
            let Some(path) = doc.path.clone() else {
                continue;
            };
            let canonical = std::fs::canonicalize(&path).ok();
            let found: Vec<Finding> = self
                .analyses
                .values()
                .flat_map(|a| &a.elsewhere)
                .filter(|f| {
                    f.file == path
                        || canonical.is_some() && std::fs::canonicalize(&f.file).ok() == canonical
                })
                .cloned()
                .collect();
            let diagnostics = Analysis::diagnose_prefab(doc, &path, &found);
            out.push(publication(uri, doc, diagnostics));
        }
    }

    /// The open prefab buffers' texts by their files' canonical paths.
    fn prefab_overlays(&self) -> HashMap<PathBuf, Arc<str>> {
        self.documents
            .uris()
            .filter_map(|uri| self.documents.get(uri))
            .filter(|doc| is_prefab(doc))
            .filter_map(|doc| {
                let canonical = std::fs::canonicalize(doc.path.as_ref()?).ok()?;
                Some((canonical, Arc::from(doc.text.as_str())))
            })
            .collect()
    }

    fn request(&mut self, method: &str, params: Value) -> Result<Value, Failure> {
        match (self.state, method) {
            (State::Uninitialized, "initialize") => {
                self.state = State::Running;
                to_json(initialize_result())
            }
            (State::Uninitialized, _) => Err((
                code::SERVER_NOT_INITIALIZED,
                "the server is not initialized: send `initialize` first".into(),
            )),
            (State::ShutDown, _) => Err((
                code::INVALID_REQUEST,
                "the server is shut down: only `exit` is accepted".into(),
            )),
            (State::Running, "initialize") => {
                Err((code::INVALID_REQUEST, "already initialized".into()))
            }
            (State::Running, "shutdown") => {
                self.state = State::ShutDown;
                Ok(Value::Null)
            }
            (State::Running, "textDocument/completion") => {
                let p: CompletionParams = parse(params)?;
                self.at(&p.text_document_position, |s, uri, doc, offset| {
                    let here = s.outline(uri);
                    to_json(CompletionResponse::Array(completion(
                        doc,
                        doc.path.as_deref(),
                        &here,
                        offset,
                    )))
                })
            }
            (State::Running, "textDocument/hover") => {
                let p: HoverParams = parse(params)?;
                self.at(&p.text_document_position_params, |s, uri, doc, offset| {
                    let here = s.outline(uri);
                    let scene = s.analyses.get(uri).and_then(|a| a.scene.as_ref());
                    to_json(hover(doc, doc.path.as_deref(), &here, scene, offset))
                })
            }
            (State::Running, "textDocument/definition") => {
                let p: GotoDefinitionParams = parse(params)?;
                let uri = p.text_document_position_params.text_document.uri.clone();
                self.at(&p.text_document_position_params, |s, key, doc, offset| {
                    let here = s.outline(key);
                    let found = doc
                        .path
                        .as_deref()
                        .and_then(|path| definition(doc, &uri, path, &here, offset));
                    to_json(found.map(GotoDefinitionResponse::Scalar))
                })
            }
            (State::Running, "textDocument/documentSymbol") => {
                let p: DocumentSymbolParams = parse(params)?;
                let uri = p.text_document.uri.as_str().to_string();
                self.cache_outline(&uri);
                let Some(doc) = self.documents.get(&uri) else {
                    return Ok(Value::Null);
                };
                let here = self.outline(&uri);
                to_json(DocumentSymbolResponse::Nested(symbols(doc, &here)))
            }
            (State::Running, _) => Err((
                code::METHOD_NOT_FOUND,
                format!(
                    "unknown method {:?}",
                    crate::scene::error::printable(method, 200)
                ),
            )),
        }
    }

    /// Answers a request about a position: `f` gets the server, the document's URI, the
    /// document and the byte offset. `null` when the document is not open.
    fn at(
        &mut self,
        p: &TextDocumentPositionParams,
        f: impl FnOnce(&Self, &str, &Document, usize) -> Result<Value, Failure>,
    ) -> Result<Value, Failure> {
        let uri = p.text_document.uri.as_str().to_string();
        self.cache_outline(&uri);
        let Some(doc) = self.documents.get(&uri) else {
            return Ok(Value::Null);
        };
        f(self, &uri, doc, doc.offset(p.position))
    }

    /// Builds the outline of `uri`, unless it is cached (outlines are dropped on each change).
    fn cache_outline(&mut self, uri: &str) {
        if !self.outlines.contains_key(uri)
            && let Some(doc) = self.documents.get(uri)
        {
            self.outlines.insert(uri.to_string(), outline(&doc.text));
        }
    }

    /// The outline of the open document `uri`: the cached one, else built now.
    fn outline(&self, uri: &str) -> std::borrow::Cow<'_, Outline> {
        match (self.outlines.get(uri), self.documents.get(uri)) {
            (Some(o), _) => std::borrow::Cow::Borrowed(o),
            (None, Some(doc)) => std::borrow::Cow::Owned(outline(&doc.text)),
            (None, None) => std::borrow::Cow::Owned(Outline::default()),
        }
    }

    fn notification(&mut self, method: &str, params: Value, out: &mut Vec<Value>) -> Flow {
        match (self.state, method) {
            (_, "exit") => return Flow::Exit(if self.state == State::ShutDown { 0 } else { 1 }),
            (State::Uninitialized, _) => {
                log(&format!("{method} before initialize: ignored"));
            }
            (_, "initialized") => {}
            (_, "textDocument/didOpen") => {
                if let Some(p) = params_or_log::<DidOpenTextDocumentParams>(method, params) {
                    let uri = p.text_document.uri.as_str().to_string();
                    let doc =
                        Document::new(to_path(&uri), p.text_document.text, p.text_document.version);
                    match self.documents.open(&uri, doc) {
                        Ok(()) => self.changed(&uri),
                        Err(e) => log(&format!("{uri}: not opened: {e}")),
                    }
                }
            }
            (_, "textDocument/didChange") => {
                if let Some(p) = params_or_log::<DidChangeTextDocumentParams>(method, params) {
                    let uri = p.text_document.uri.as_str().to_string();
                    match self
                        .documents
                        .change(&uri, p.text_document.version, p.content_changes)
                    {
                        Ok(()) => self.changed(&uri),
                        Err(e) => {
                            log(&format!("{uri}: change not applied, document closed: {e}"));
                            self.forget(&uri, out);
                        }
                    }
                }
            }
            (_, "textDocument/didClose") => {
                if let Some(p) = params_or_log::<DidCloseTextDocumentParams>(method, params) {
                    let uri = p.text_document.uri.as_str().to_string();
                    match self.documents.get(&uri).map(is_prefab) {
                        Some(true) => self.prefab_closed = true,
                        Some(false) => self.scene_closed = true,
                        None => {}
                    }
                    self.documents.close(&uri);
                    self.forget(&uri, out);
                }
            }
            // A file saved or changed on disk may be a prefab, mesh or texture of any open
            // scene: every asset is read again, every document analysed again.
            (_, "textDocument/didSave" | "workspace/didChangeWatchedFiles") => {
                for a in self.analyses.values_mut() {
                    a.files_changed();
                }
                self.dirty.extend(self.documents.uris().cloned());
            }
            (_, m) if m.starts_with("$/") => {}
            (_, m) => log(&format!(
                "unknown notification {:?}: ignored",
                crate::scene::error::printable(m, 200)
            )),
        }
        Flow::Continue
    }

    /// Marks `uri` changed: its outline is stale and its diagnostics to be published.
    fn changed(&mut self, uri: &str) {
        self.outlines.remove(uri);
        self.dirty.insert(uri.to_string());
    }

    /// Drops what is kept for `uri` and clears its diagnostics in the editor.
    fn forget(&mut self, uri: &str, out: &mut Vec<Value>) {
        self.outlines.remove(uri);
        self.analyses.remove(uri);
        self.dirty.remove(uri);
        let cleared = PublishDiagnosticsParams {
            uri: match uri.parse() {
                Ok(u) => u,
                Err(_) => return,
            },
            diagnostics: Vec::new(),
            version: None,
        };
        if let Ok(params) = serde_json::to_value(cleared) {
            out.push(notification("textDocument/publishDiagnostics", params));
        }
    }
}

/// Whether `doc` is a prefab file (its top-level value is a `Prefab`).
fn is_prefab(doc: &Document) -> bool {
    top_name(&doc.text) == "Prefab"
}

/// The `publishDiagnostics` notification of `doc`.
fn publication(uri: &str, doc: &Document, diagnostics: Vec<lsp_types::Diagnostic>) -> Value {
    notification(
        "textDocument/publishDiagnostics",
        json!({"uri": uri, "version": doc.version, "diagnostics": diagnostics}),
    )
}

/// What the server can do.
fn initialize_result() -> InitializeResult {
    InitializeResult {
        capabilities: ServerCapabilities {
            text_document_sync: Some(TextDocumentSyncCapability::Options(
                TextDocumentSyncOptions {
                    open_close: Some(true),
                    change: Some(TextDocumentSyncKind::INCREMENTAL),
                    save: Some(TextDocumentSyncSaveOptions::SaveOptions(SaveOptions {
                        include_text: Some(false),
                    })),
                    ..TextDocumentSyncOptions::default()
                },
            )),
            completion_provider: Some(CompletionOptions {
                trigger_characters: Some(["\"", "/", "(", ",", ":"].map(String::from).to_vec()),
                ..CompletionOptions::default()
            }),
            hover_provider: Some(HoverProviderCapability::Simple(true)),
            definition_provider: Some(OneOf::Left(true)),
            document_symbol_provider: Some(OneOf::Left(true)),
            ..ServerCapabilities::default()
        },
        server_info: Some(ServerInfo {
            name: "rondo".into(),
            version: Some(env!("CARGO_PKG_VERSION").into()),
        }),
    }
}

/// A JSON-RPC error response.
fn error(id: Value, code: i64, message: String) -> Value {
    json!({"jsonrpc": "2.0", "id": id, "error": {"code": code, "message": message}})
}

/// A notification to the client.
fn notification(method: &str, params: Value) -> Value {
    json!({"jsonrpc": "2.0", "method": method, "params": params})
}

/// A request's parameters as `T`, or the -32602 error.
fn parse<T: DeserializeOwned>(params: Value) -> Result<T, Failure> {
    serde_json::from_value(params).map_err(|e| (code::INVALID_PARAMS, format!("bad params: {e}")))
}

/// A notification's parameters as `T`; logged and `None` when they do not fit.
fn params_or_log<T: DeserializeOwned>(method: &str, params: Value) -> Option<T> {
    serde_json::from_value(params)
        .map_err(|e| log(&format!("{method}: bad params: {e}")))
        .ok()
}

/// A result as JSON.
fn to_json(value: impl serde::Serialize) -> Result<Value, Failure> {
    serde_json::to_value(value).map_err(|e| (code::INVALID_PARAMS, e.to_string()))
}

/// One line on standard error (the client shows it in its log), bounded and escaped.
pub fn log(message: &str) {
    eprintln!(
        "rondo lsp: {}",
        crate::scene::error::printable(message, 2000)
    );
}
