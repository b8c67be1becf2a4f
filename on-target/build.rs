//! Picks the memory layout of the emulated board for the target: the Cortex-M4F board
//! (mps2-an386: 4 MiB of flash and of RAM) for thumbv7em, the BBC micro:bit (nRF51, Cortex-M0:
//! 256 KiB of flash, 16 KiB of RAM) for thumbv6m, so the M0 tests run in the RAM a real M0 has.
use std::{env, fs, path::PathBuf};

fn main() {
    let out = PathBuf::from(env::var_os("OUT_DIR").unwrap_or_default());
    let target = env::var("TARGET").unwrap_or_default();
    let memory = if target.starts_with("thumbv6m") {
        "memory-microbit.x"
    } else {
        "memory-an386.x"
    };
    let _ = fs::copy(memory, out.join("memory.x"));
    // `cfg(micro_bit)`: 16 KiB of RAM, too little for the 256-entry timer queue and tracker of
    // the `cycles` firmware.
    println!("cargo:rustc-check-cfg=cfg(micro_bit)");
    if target.starts_with("thumbv6m") {
        println!("cargo:rustc-cfg=micro_bit");
    }
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed=memory-microbit.x");
    println!("cargo:rerun-if-changed=memory-an386.x");
}
