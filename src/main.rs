//! The `mpsfsi` command: parse the command line and dispatch (see `cli/`).

mod cli;

fn main() {
    let code = cli::main(<cli::Cli as clap::Parser>::parse());
    std::process::exit(code);
}
