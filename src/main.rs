//! The `penumbra` command line. main dispatches only: each command lives in
//! its own module under src/cli/.

use std::process::ExitCode;

use clap::Parser;

use penumbra::terminal;

mod cli;

fn main() -> ExitCode {
    let cli = cli::Cli::parse();
    // A panic is a bug, not a way to report input: should one still happen,
    // one `error:` line names the file, the panic unwinds (removing any
    // temporary output file) and the exit status is 70 (EX_SOFTWARE).
    penumbra::panics::install_hook();
    if let Some(subject) = cli.subject() {
        penumbra::panics::set_subject(subject);
    }
    match std::panic::catch_unwind(|| cli.run()) {
        Ok(Ok(())) => ExitCode::SUCCESS,
        Ok(Err(e)) => {
            eprintln!("error: {}", terminal::diagnostic(&format!("{e:#}")));
            if penumbra::render::is_timeout(&e) {
                cli::exit_leaving_the_device(1);
            }
            ExitCode::FAILURE
        }
        Err(_) => ExitCode::from(70),
    }
}
