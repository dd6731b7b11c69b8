//! `cargo fw-image` and `cargo fw-emu`: the firmware image for the ESP8266
//! and that image booted on the project's emulated board.
use std::process::ExitCode;

mod callgraph;
mod elf;
mod emu;
mod esptool;
mod image;
mod patch;
mod rewrite;
mod stack;

const USAGE: &str = "\
usage: cargo fw-image [--help]
       cargo fw-emu [--help] [options]
       cargo run --manifest-path xtask/Cargo.toml -- fw-check [ELF]

fw-image  builds the firmware for the ESP8266 with upstream nightly into
          target/image/ (ELF and the two flash images) and checks it
fw-emu    boots target/image/ on the emulated ESP8266 (emu/)
fw-check  fw-image's checks (the stack's depth among them) on an ELF
          already built, target/image/paperbot.elf unless named";

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (task, rest) = match args.split_first() {
        Some((task, rest)) => (task.as_str(), rest),
        None => ("", &[][..]),
    };
    let result = match task {
        "fw-image" => image::main(rest),
        "fw-emu" => emu::main(rest),
        "fw-check" => image::check_only(rest),
        "--help" | "-h" => {
            println!("{USAGE}");
            return ExitCode::SUCCESS;
        }
        _ => Err(format!("unknown task '{task}'\n{USAGE}")),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
