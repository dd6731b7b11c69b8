//! esptool (Espressif's flashing tool, from PyPI) in a virtual environment
//! of its own under `target/image/`: `elf2image` writes the flash images
//! with the module's flash parameters in the boot image's header,
//! `image-info` must accept the boot image and report those parameters.
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::image::run;

/// The esptool release the images are made and checked with.
const ESPTOOL: &str = "esptool==5.6.0";

/// The flash parameters the ROM reads from the boot image's header (byte 2
/// the mode, byte 3 the size and the clock). Without them `elf2image`
/// writes QIO, 1 MB, 40 MHz, and `write-flash` keeps the header; esptool's
/// documentation ("Flash Modes") says the ESP-12E modules of some NodeMCU
/// boards boot only with `dio`. Defaults: the NodeMCU's ESP-12E, DIO flash
/// of 4 MB at 40 MHz.
#[derive(Clone, Debug, PartialEq)]
pub struct FlashParams {
    pub mode: String,
    pub freq: String,
    pub size: String,
}

impl Default for FlashParams {
    fn default() -> Self {
        FlashParams { mode: "dio".into(), freq: "40m".into(), size: "4MB".into() }
    }
}

impl FlashParams {
    /// An error naming the value esptool's ESP8266 images cannot hold.
    pub fn validate(&self) -> Result<(), String> {
        const MODES: [&str; 4] = ["qio", "qout", "dio", "dout"];
        const FREQS: [&str; 4] = ["40m", "26m", "20m", "80m"];
        const SIZES: [&str; 9] = ["256KB", "512KB", "1MB", "2MB", "2MB-c1", "4MB", "4MB-c1", "8MB", "16MB"];
        let check = |what: &str, v: &str, ok: &[&str]| {
            if ok.contains(&v) {
                Ok(())
            } else {
                Err(format!("--flash-{what} '{v}': the ESP8266's are {}", ok.join(", ")))
            }
        };
        check("mode", &self.mode, &MODES)?;
        check("freq", &self.freq, &FREQS)?;
        check("size", &self.size, &SIZES)
    }

    /// What `image-info` prints for them ("Flash mode: DIO" ...), in order.
    fn image_info_lines(&self) -> [String; 3] {
        [
            format!("Flash size: {}", self.size),
            format!("Flash freq: {}", self.freq),
            format!("Flash mode: {}", self.mode.to_uppercase()),
        ]
    }
}

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

/// `<prefix>0x00000.bin` and `<prefix>0x10000.bin` from the ELF, checked:
/// `image-info` must report the flash parameters asked for.
pub fn write_images(root: &Path, elf: &Path, prefix: &Path, flash: &FlashParams) -> Result<(), String> {
    let boot = boot_image(root, elf, prefix, flash)?;
    let irom = PathBuf::from(format!("{}0x10000.bin", prefix.display()));
    for f in [&boot, &irom] {
        let len = std::fs::metadata(f).map_err(|e| format!("{}: {e}", f.display()))?.len();
        println!("  {} ({len} B)", f.display());
    }
    let text = image_info(root, &boot)?;
    check_flash_params(&text, flash)?;
    let shown = ["Entry point", "Checksum", "Segments:", "Flash size", "Flash freq", "Flash mode"];
    for line in text.lines().filter(|l| shown.iter().any(|s| l.starts_with(s))) {
        println!("  image-info: {}", line.trim());
    }
    Ok(())
}

/// An error unless `image-info`'s text reports each of the parameters.
fn check_flash_params(image_info: &str, flash: &FlashParams) -> Result<(), String> {
    let lines: Vec<&str> = image_info.lines().map(str::trim).collect();
    let missing: Vec<String> =
        flash.image_info_lines().into_iter().filter(|want| !lines.contains(&want.as_str())).collect();
    if missing.is_empty() {
        Ok(())
    } else {
        Err(format!("esptool image-info does not report {}:\n{image_info}", missing.join(", ")))
    }
}

/// esptool's `elf2image`: the boot image `<prefix>0x00000.bin` (and, if the
/// ELF has code mapped from flash, `<prefix>0x10000.bin`) with the flash
/// parameters in its header; its path.
pub fn boot_image(root: &Path, elf: &Path, prefix: &Path, flash: &FlashParams) -> Result<PathBuf, String> {
    let esptool = esptool(root)?;
    // Version 1 images: the boot image holds the RAM segments, the code
    // mapped from flash at 0x40210000 goes to flash offset 0x10000.
    let out = Command::new(&esptool)
        .args(["--chip", "esp8266", "elf2image", "--version", "1"])
        .args(["--flash-mode", &flash.mode, "--flash-freq", &flash.freq, "--flash-size", &flash.size])
        .arg("-o")
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

#[cfg(test)]
mod tests {
    use super::*;

    const INFO: &str =
        "Image version: 1\nEntry point: 0x401001b4\nSegments: 3\nFlash size: 4MB\nFlash freq: 40m\nFlash mode: DIO\n";

    #[test]
    fn the_header_must_report_what_was_asked() {
        assert!(check_flash_params(INFO, &FlashParams::default()).is_ok());
        let qio = INFO.replace("DIO", "QIO");
        let e = check_flash_params(&qio, &FlashParams::default()).unwrap_err();
        assert!(e.contains("Flash mode: DIO"), "{e}");
        let one_mb = FlashParams { size: "1MB".into(), ..FlashParams::default() };
        assert!(check_flash_params(INFO, &one_mb).unwrap_err().contains("Flash size: 1MB"));
    }

    #[test]
    fn flash_params_are_the_esp8266s() {
        assert!(FlashParams::default().validate().is_ok());
        assert!(FlashParams { mode: "dout".into(), ..FlashParams::default() }.validate().is_ok());
        assert!(FlashParams { mode: "fast".into(), ..FlashParams::default() }.validate().is_err());
        assert!(FlashParams { size: "3MB".into(), ..FlashParams::default() }.validate().is_err());
    }
}
