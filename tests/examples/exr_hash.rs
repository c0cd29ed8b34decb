//! Prints a hash of every pixel value of each EXR or PNG given (the beauty and every pass; not
//! the header, whose render time and date differ from run to run), so two builds' images can be
//! compared bit for bit: `cargo run -p aperture-tests --example exr_hash -- A.exr B.exr`.

fn fnv(h: &mut u64, bytes: &[u8]) {
    for b in bytes {
        *h ^= u64::from(*b);
        *h = h.wrapping_mul(0x0100_0000_01b3);
    }
}

fn main() {
    let mut failed = false;
    for path in std::env::args().skip(1) {
        let image = if path.ends_with(".png") {
            std::fs::read(&path)
                .map(|b| vec![b])
                .map_err(|e| e.to_string())
        } else {
            aperture_imageio::read_exr(path.as_ref())
                .map(|im| {
                    let mut parts = vec![im
                        .rgba
                        .iter()
                        .flatten()
                        .flat_map(|v| v.to_le_bytes())
                        .collect()];
                    for l in &im.layers {
                        let mut bytes = l.name.as_bytes().to_vec();
                        bytes.extend(l.data.iter().flat_map(|v| v.to_le_bytes()));
                        parts.push(bytes);
                    }
                    parts
                })
                .map_err(|e| e.to_string())
        };
        match image {
            Ok(parts) => {
                let mut h = 0xcbf2_9ce4_8422_2325u64;
                for p in &parts {
                    fnv(&mut h, p);
                }
                println!("{h:016x}  {path}");
            }
            Err(e) => {
                eprintln!("{path}: {e}");
                failed = true;
            }
        }
    }
    std::process::exit(i32::from(failed));
}
