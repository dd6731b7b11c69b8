//! esptool (Espressif's flashing tool, from PyPI) in a virtual environment
//! of its own under `target/image/`: `elf2image` writes the flash images,
//! `image-info` must accept the boot image.
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::image::run;

/// The esptool release the images are made and checked with.
const ESPTOOL: &str = "esptool==5.6.0";

/// The venv's esptool, installed on first use.
fn esptool(root: &Path) -> Result<PathBuf, String> {
    let venv = root.join("target/image/esptool-venv");
    let bin = venv.join("bin/esptool");
    if !bin.is_file() {
        println!("  installing {ESPTOOL} into {}", venv.display());
        run(Command::new("python3").args(["-m", "venv"]).arg(&venv))
            .map_err(|e| format!("{e}\n(python3 with venv needed: apt-get install python3-venv)"))?;
        run(Command::new(venv.join("bin/pip")).args(["install", "--quiet", ESPTOOL]))?;
    }
    Ok(bin)
}

/// `<prefix>0x00000.bin` and `<prefix>0x10000.bin` from the ELF, checked.
pub fn write_images(root: &Path, elf: &Path, prefix: &Path) -> Result<(), String> {
    let boot = boot_image(root, elf, prefix)?;
    let flash = PathBuf::from(format!("{}0x10000.bin", prefix.display()));
    for f in [&boot, &flash] {
        let len = std::fs::metadata(f).map_err(|e| format!("{}: {e}", f.display()))?.len();
        println!("  {} ({len} B)", f.display());
    }
    let text = image_info(root, &boot)?;
    for line in text.lines().filter(|l| l.contains("Entry point") || l.contains("Checksum") || l.contains("Segments")) {
        println!("  image-info: {}", line.trim());
    }
    Ok(())
}

/// esptool's `elf2image`: the boot image `<prefix>0x00000.bin` (and, if the
/// ELF has code mapped from flash, `<prefix>0x10000.bin`); its path.
pub fn boot_image(root: &Path, elf: &Path, prefix: &Path) -> Result<PathBuf, String> {
    let esptool = esptool(root)?;
    // Version 1 images: the boot image holds the RAM segments, the code
    // mapped from flash at 0x40210000 goes to flash offset 0x10000.
    let out = Command::new(&esptool)
        .args(["--chip", "esp8266", "elf2image", "--version", "1", "-o"])
        .arg(prefix)
        .arg(elf)
        .output()
        .map_err(|e| format!("{}: {e}", esptool.display()))?;
    if !out.status.success() {
        return Err(format!(
            "esptool elf2image failed:\n{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    Ok(PathBuf::from(format!("{}0x00000.bin", prefix.display())))
}

/// esptool's `image-info` of a boot image, which it must accept with a
/// valid checksum; its text.
fn image_info(root: &Path, boot: &Path) -> Result<String, String> {
    let esptool = esptool(root)?;
    let info = Command::new(&esptool)
        .args(["--chip", "esp8266", "image-info"])
        .arg(boot)
        .output()
        .map_err(|e| format!("{}: {e}", esptool.display()))?;
    let text = String::from_utf8_lossy(&info.stdout).into_owned() + &String::from_utf8_lossy(&info.stderr);
    if !info.status.success() || !text.contains("(valid)") {
        return Err(format!("esptool image-info does not accept {}:\n{text}", boot.display()));
    }
    Ok(text)
}
