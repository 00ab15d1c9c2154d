//! The `propid` command: the library's [`propid::run`] on the process's arguments.

fn main() -> std::process::ExitCode {
    propid::run(std::env::args_os())
}
