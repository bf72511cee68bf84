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
    /// Every estimator (ours and peers) over the same logs: accuracy, cost, figures.
    Compare(sim_harness::compare::CompareArgs),
}

fn main() {
    let cli = Cli::parse();
    let res = match cli.cmd {
        Cmd::Demo => demo(),
        Cmd::Compare(a) => sim_harness::compare::run(&a).map(|_| ()),
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
