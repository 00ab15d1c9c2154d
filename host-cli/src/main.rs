//! The `propid` command: a thin argument parser over the `propid` library ([`propid::cli`]).

use std::process::ExitCode;

fn main() -> ExitCode {
    propid::run(std::env::args_os())
}
