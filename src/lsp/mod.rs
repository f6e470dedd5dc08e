//! `rondo lsp`: a language server for scene and prefab files (LSP 3.17 over standard input and
//! output), for any editor with an LSP client.
//!
//! - diagnostics as you type, for the buffer (not the file on disk), from the loader and
//!   `rondo check` ([`diagnostics`]);
//! - document symbols: materials and entities ([`symbols`]);
//! - go to definition: a material name to its definition (in the file, or in the prefab a
//!   placement maps it from), a path to its file ([`definition`]);
//! - completion: material names, field names and kinds from the format's own types, paths
//!   ([`completion`]);
//! - hover: a material's definition, an entity's world bounds, what a placement places
//!   ([`hover`]).
//!
//! The protocol: [`transport`] (bounded framing), [`server`] (lifecycle and dispatch),
//! [`stdio`] (the loop); the buffers: [`documents`]; reading them while they are typed:
//! [`syntax`], [`outline`], [`reference`](mod@reference), [`probe`]; [`uri`] maps URIs to paths.

pub mod completion;
pub mod definition;
pub mod diagnostics;
pub mod documents;
pub mod hover;
pub mod outline;
pub mod probe;
pub mod reference;
pub mod server;
pub mod stdio;
pub mod symbols;
pub mod syntax;
pub mod transport;
pub mod uri;

pub use stdio::serve_stdio;
