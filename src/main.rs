//! The `cogeo` binary: parse the command line, run the subcommand (src/cli), and report an error
//! as one line naming its causes.

mod cli;

use clap::Parser;

fn main() {
    let cli = cli::Cli::parse();
    if let Err(e) = cli::dispatch(cli.command) {
        // one line: the error and its causes
        let chain: Vec<String> = e.chain().map(|c| c.to_string()).collect();
        eprintln!("error: {}", chain.join(": "));
        // `batch run` tells a scheduler whether a retry can help (cli/batch.rs)
        std::process::exit(e.downcast_ref::<cli::batch::Exit>().map_or(1, |x| x.code()));
    }
}
