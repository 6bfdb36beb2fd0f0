//! The `mpsfsi` command (placeholder CLI: run only).

use clap::{Parser, Subcommand};
use std::path::PathBuf;

#[derive(Parser)]
#[command(name = "mpsfsi", version, about = "2D MPS fluid-structure simulation")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a case and write the run directory.
    Run {
        case: PathBuf,
        #[arg(long)]
        out: PathBuf,
        #[arg(long = "set", value_name = "PATH=VALUE")]
        set: Vec<String>,
    },
}

fn main() {
    let cli = Cli::parse();
    match cli.command {
        Command::Run { case, out, set } => {
            let case = match mpsfsi::case::load_case_file(&case, &set) {
                Ok(c) => c,
                Err(e) => {
                    eprintln!("error: {e}");
                    std::process::exit(2);
                }
            };
            match mpsfsi::run::run_case(&case, &out, &mut mpsfsi::run::Quiet) {
                Ok(s) => {
                    println!("{}", serde_json::to_string_pretty(&s).unwrap());
                    if s.status != mpsfsi::run::RunStatus::Succeeded {
                        std::process::exit(1);
                    }
                }
                Err(e) => {
                    eprintln!("error: {e}");
                    std::process::exit(2);
                }
            }
        }
    }
}
