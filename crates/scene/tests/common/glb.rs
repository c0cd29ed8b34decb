//! Binary glTF written by tests.

use serde_json::Value;

/// The GLB container of `doc` and `bin`: JSON chunk and BIN chunk, each padded to 4 bytes.
pub fn glb(doc: &Value, bin: &[u8]) -> Vec<u8> {
    let mut js = serde_json::to_vec(doc).unwrap();
    while js.len() % 4 != 0 {
        js.push(b' ');
    }
    let mut bin = bin.to_vec();
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let total = 12 + 8 + js.len() + 8 + bin.len();
    let mut out = b"glTF".to_vec();
    for v in [2, total as u32, js.len() as u32, 0x4E4F_534A] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&js);
    for v in [bin.len() as u32, 0x004E_4942] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&bin);
    out
}
