//! Project chores: `cargo xtask <command>` (the alias lives in `.cargo/config.toml`).

use std::process::ExitCode;

const HELP: &str = "\
cargo xtask <command>

Commands:
  validate-shaders   Parse and validate every WGSL file of the shaders crate with naga
  help               Print this message
";

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        None | Some("help" | "-h" | "--help") => {
            print!("{HELP}");
            ExitCode::SUCCESS
        }
        Some("validate-shaders") => validate_shaders(),
        Some(other) => {
            eprintln!("xtask: unknown command {other:?}\n\n{HELP}");
            ExitCode::FAILURE
        }
    }
}

fn validate_shaders() -> ExitCode {
    match check_shaders() {
        Ok(n) => {
            println!("validated {n} shaders");
            ExitCode::SUCCESS
        }
        Err(errors) => {
            for e in &errors {
                eprintln!("{e}");
            }
            eprintln!("validate-shaders: {} error(s)", errors.len());
            ExitCode::FAILURE
        }
    }
}

/// Composes, parses and validates every WGSL shader of `dirt-shaders` with
/// naga: the number of stage files validated, or every error as
/// `module.wgsl:line:col: message`.
fn check_shaders() -> Result<usize, Vec<String>> {
    dirt_shaders::validate_all()?;
    Ok(dirt_shaders::entries().len())
}

#[cfg(test)]
mod tests {
    /// `cargo test` alone runs the same check as `cargo xtask validate-shaders`.
    #[test]
    fn validate_shaders() {
        match super::check_shaders() {
            Ok(n) => assert!(n >= 1, "no shaders found"),
            Err(errors) => panic!("shader validation failed:\n{}", errors.join("\n")),
        }
    }
}
