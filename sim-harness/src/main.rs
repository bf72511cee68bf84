//! `sim-harness` command line.
use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(name = "sim-harness", version, about = "Simulate, replay, measure and check the wing-ahrs estimator")]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Short built-in demo: replay a synthetic coordinated turn and print the attitude.
    Demo,
}

fn main() {
    let cli = Cli::parse();
    let res = match cli.cmd {
        Cmd::Demo => demo(),
    };
    if let Err(e) = res {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

fn demo() -> anyhow::Result<()> {
    println!("demo: not yet wired");
    Ok(())
}
