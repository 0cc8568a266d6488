//! `station`: see `station --help`. Everything lives in the library; this only runs it.

fn main() -> std::process::ExitCode {
    station::headless::run()
}
