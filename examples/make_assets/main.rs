//! Regenerates `assets/`: the mannequin's control mesh and its animated OBJ sequence, the cape
//! and the skirt. Deterministic: running it again rewrites the same bytes.
//!
//!     cargo run --release --example make_assets

mod generate;

use std::fs;
use std::path::Path;

fn main() -> std::io::Result<()> {
    let generated = generate::generate();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets");
    let mut bytes = 0;
    for asset in &generated.assets {
        let path = root.join(&asset.path);
        fs::create_dir_all(path.parent().expect("assets live in folders"))?;
        fs::write(&path, &asset.text)?;
        bytes += asset.text.len();
    }
    print!("{}", generated.summary);
    println!(
        "wrote {} files, {} KiB, under {}",
        generated.assets.len(),
        bytes / 1024,
        root.display()
    );
    Ok(())
}
