//! The `vlab` command line.

fn main() {
    println!("vlab {}", env!("CARGO_PKG_VERSION"));
}
