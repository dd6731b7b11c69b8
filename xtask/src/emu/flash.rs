//! Flash contents for the board: the two files of `cargo fw-image` placed at
//! their flash offsets, as a flasher writes them; and, for the self-test's
//! watchdog image, an ESP8266 boot image made from a small ELF.

/// Where the flash-mapped code goes (`paperbot-0x10000.bin`, memory.x).
pub const IROM_OFFSET: usize = 0x10000;
const ERASED: u8 = 0xff;

/// The flash as written by `esptool write_flash 0x0 boot 0x10000 irom`.
pub fn compose(boot: &[u8], irom: &[u8]) -> Result<Vec<u8>, String> {
    if boot.len() > IROM_OFFSET {
        return Err(format!("boot image is {} B, over the {IROM_OFFSET:#x} B before the flash code", boot.len()));
    }
    let mut flash = vec![ERASED; IROM_OFFSET + irom.len()];
    flash[..boot.len()].copy_from_slice(boot);
    flash[IROM_OFFSET..].copy_from_slice(irom);
    Ok(flash)
}

/// esptool's "version 1" ESP8266 boot image of the ELF's loadable segments
/// (the format the board's ROM reads, emu/rom/reset.S): header (magic
/// 0xE9, segment count, flash mode, size/frequency, entry), each segment as
/// address, length, data padded to 4 bytes, then zeros up to the last byte
/// of a 16-byte block, which is the checksum (0xEF XOR every data byte).
pub fn boot_image_from_elf(elf: &[u8]) -> Result<Vec<u8>, String> {
    let (entry, segments) = elf_segments(elf)?;
    let count = u8::try_from(segments.len()).map_err(|_| "too many segments".to_string())?;
    let mut image = vec![0xe9, count, 0, 0];
    image.extend_from_slice(&entry.to_le_bytes());
    let mut checksum = 0xefu8;
    for (addr, data) in segments {
        let mut data = data.to_vec();
        data.resize(data.len().next_multiple_of(4), 0);
        image.extend_from_slice(&addr.to_le_bytes());
        image.extend_from_slice(&(data.len() as u32).to_le_bytes());
        image.extend_from_slice(&data);
        checksum = data.iter().fold(checksum, |c, b| c ^ b);
    }
    image.resize(image.len() / 16 * 16 + 15, 0);
    image.push(checksum);
    Ok(image)
}

/// A loadable segment: its address and bytes.
type Segment<'a> = (u32, &'a [u8]);

/// Entry point and the PT_LOAD segments with data of a little-endian 32-bit
/// ELF.
fn elf_segments(elf: &[u8]) -> Result<(u32, Vec<Segment<'_>>), String> {
    let u16_at = |o: usize| elf.get(o..o + 2).map(|b| u16::from_le_bytes([b[0], b[1]]));
    let u32_at = |o: usize| elf.get(o..o + 4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
    let short = || "ELF too short".to_string();
    if elf.get(..6) != Some(&[0x7f, b'E', b'L', b'F', 1, 1][..]) {
        return Err("not a little-endian 32-bit ELF".into());
    }
    let entry = u32_at(0x18).ok_or_else(short)?;
    let phoff = u32_at(0x1c).ok_or_else(short)? as usize;
    let phentsize = usize::from(u16_at(0x2a).ok_or_else(short)?);
    let phnum = usize::from(u16_at(0x2c).ok_or_else(short)?);
    let mut segments = Vec::new();
    for i in 0..phnum {
        let ph = phoff + i * phentsize;
        let field = |n: usize| u32_at(ph + 4 * n).ok_or_else(short);
        let (p_type, offset, vaddr, filesz) = (field(0)?, field(1)? as usize, field(2)?, field(4)? as usize);
        const PT_LOAD: u32 = 1;
        if p_type == PT_LOAD && filesz > 0 {
            segments.push((vaddr, elf.get(offset..offset + filesz).ok_or_else(short)?));
        }
    }
    Ok((entry, segments))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compose_places_the_code_at_0x10000() {
        let flash = compose(&[1, 2, 3], &[9, 8]).unwrap();
        assert_eq!(flash.len(), 0x10002);
        assert_eq!(&flash[..4], &[1, 2, 3, ERASED]);
        assert_eq!(&flash[0x10000..], &[9, 8]);
        assert!(compose(&vec![0; 0x10001], &[]).is_err());
    }

    /// A hand-made ELF with one 5-byte segment at 0x40100000.
    fn tiny_elf() -> Vec<u8> {
        let mut elf = vec![0u8; 0x60];
        elf[..6].copy_from_slice(&[0x7f, b'E', b'L', b'F', 1, 1]);
        elf[0x18..0x1c].copy_from_slice(&0x4010_0004u32.to_le_bytes()); // entry
        elf[0x1c..0x20].copy_from_slice(&0x34u32.to_le_bytes()); // phoff
        elf[0x2a..0x2c].copy_from_slice(&32u16.to_le_bytes());
        elf[0x2c..0x2e].copy_from_slice(&1u16.to_le_bytes());
        let ph = [1u32, 0x58, 0x4010_0000, 0x4010_0000, 5, 5];
        for (i, v) in ph.iter().enumerate() {
            elf[0x34 + 4 * i..0x38 + 4 * i].copy_from_slice(&v.to_le_bytes());
        }
        elf[0x58..0x5d].copy_from_slice(&[0x11, 0x22, 0x33, 0x44, 0x55]);
        elf
    }

    #[test]
    fn boot_image_layout_and_checksum() {
        let image = boot_image_from_elf(&tiny_elf()).unwrap();
        assert_eq!(&image[..8], &[0xe9, 1, 0, 0, 0x04, 0x00, 0x10, 0x40]);
        assert_eq!(&image[8..16], &[0x00, 0x00, 0x10, 0x40, 8, 0, 0, 0]);
        assert_eq!(&image[16..24], &[0x11, 0x22, 0x33, 0x44, 0x55, 0, 0, 0]);
        assert_eq!(image.len(), 32, "padded to the end of a 16-byte block");
        assert_eq!(image[31], 0xef ^ 0x11 ^ 0x22 ^ 0x33 ^ 0x44 ^ 0x55);
    }

    #[test]
    fn not_an_elf_is_refused() {
        assert!(boot_image_from_elf(b"hello").is_err());
    }
}
