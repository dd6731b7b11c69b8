//! Flash contents for the board: the two files of `cargo fw-image` placed at
//! their flash offsets, as a flasher writes them.

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
}
