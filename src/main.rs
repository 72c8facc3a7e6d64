//! The `dyncontact` executable: the command line of [`dyncontact::cli`] with this process's
//! arguments.

fn main() -> std::process::ExitCode {
    std::process::ExitCode::from(dyncontact::cli::main(std::env::args_os(), None))
}
