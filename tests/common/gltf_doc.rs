//! glTF documents written by the tests: binary buffers, JSON with data-URI buffers, `.glb`
//! containers assembled byte by byte.

use serde_json::{Value, json};

/// Standard base64 with padding.
pub fn base64(data: &[u8]) -> String {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in data.chunks(3) {
        let n = u32::from(c[0]) << 16
            | u32::from(*c.get(1).unwrap_or(&0)) << 8
            | u32::from(*c.get(2).unwrap_or(&0));
        for k in 0..4 {
            if k <= c.len() {
                s.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// A binary buffer under construction; each appended view returns its index.
#[derive(Default)]
pub struct Bin {
    /// The buffer's bytes.
    pub bytes: Vec<u8>,
    /// Its buffer views.
    pub views: Vec<Value>,
}

impl Bin {
    /// Appends `data` (4-byte aligned) as a new view; returns its index.
    pub fn view(&mut self, data: Vec<u8>) -> usize {
        while !self.bytes.len().is_multiple_of(4) {
            self.bytes.push(0);
        }
        self.views
            .push(json!({"buffer": 0, "byteOffset": self.bytes.len(), "byteLength": data.len()}));
        self.bytes.extend(data);
        self.views.len() - 1
    }
    /// Appends floats as a view.
    pub fn f32s(&mut self, v: &[f32]) -> usize {
        self.view(v.iter().flat_map(|x| x.to_le_bytes()).collect())
    }
    /// Appends u16s as a view.
    pub fn u16s(&mut self, v: &[u16]) -> usize {
        self.view(v.iter().flat_map(|x| x.to_le_bytes()).collect())
    }
}

/// A document from `bin`'s views and the given parts, its buffer a data URI.
pub fn doc(bin: &Bin, mut parts: Value) -> Value {
    parts["asset"] = json!({"version": "2.0"});
    parts["bufferViews"] = Value::Array(bin.views.clone());
    parts["buffers"] = json!([{
        "byteLength": bin.bytes.len(),
        "uri": format!("data:application/octet-stream;base64,{}", base64(&bin.bytes)),
    }]);
    parts
}

/// `doc` with its buffer in a `.glb` binary chunk.
pub fn glb(bin: &Bin, parts: Value) -> Vec<u8> {
    let mut d = doc(bin, parts);
    d["buffers"] = json!([{"byteLength": bin.bytes.len()}]);
    let mut json = d.to_string().into_bytes();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut data = bin.bytes.clone();
    while !data.len().is_multiple_of(4) {
        data.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + data.len();
    let mut out = Vec::new();
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(json);
    out.extend((data.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(data);
    out
}

/// A glTF file of one node "sign": the unit square [0, 1]² at z = 0, two triangles.
pub fn square_panel() -> String {
    let mut bin = Bin::default();
    let v = bin.f32s(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.0]);
    let i = bin.u16s(&[0, 1, 2, 0, 2, 3]);
    let parts = json!({
        "accessors": [
            {"bufferView": v, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]},
            {"bufferView": i, "componentType": 5123, "count": 6, "type": "SCALAR"},
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "nodes": [{"mesh": 0, "name": "sign"}],
        "scenes": [{"nodes": [0]}],
        "scene": 0,
    });
    doc(&bin, parts).to_string()
}
