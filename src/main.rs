//! The `skytie` binary: see `skytie --help` and `skytie::cli`.

fn main() {
    std::process::exit(skytie::cli::main());
}
