//! What every footprint firmware shares: measuring the stack a call uses (feature `measure`,
//! under QEMU), or nothing at all (the build whose flash is measured).
#![no_std]

/// Runs `f` and returns its result; with the feature `measure`, also prints how many bytes of
/// stack `f` used at its deepest, as `stack <name> <bytes>`.
///
/// The stack below the caller is painted afresh first (cortex-m-rt paints it once at reset, but
/// an earlier call may have scrubbed it), then the lowest word no longer painted marks the depth.
/// Without the feature it is `f()`, inlined like any call the firmware makes.
#[inline(always)]
pub fn stack<R>(name: &str, f: impl FnOnce() -> R) -> R {
    #[cfg(feature = "measure")]
    {
        measure::stack(name, f)
    }
    #[cfg(not(feature = "measure"))]
    {
        let _ = name;
        f()
    }
}

/// Whether this is the measuring build: the measured calls run (three times each, the first may
/// differ) only there, so they add no code to the build whose flash is measured.
pub const MEASURING: bool = cfg!(feature = "measure");

/// The end of a firmware: exits QEMU when measuring, else loops for ever.
pub fn finish() -> ! {
    #[cfg(feature = "measure")]
    cortex_m_semihosting::debug::exit(cortex_m_semihosting::debug::EXIT_SUCCESS);
    loop {
        cortex_m::asm::nop();
    }
}

/// Stops the firmware when its configuration is refused (it never is: the stored values are
/// valid); an exit with failure when measuring.
pub fn refused() -> ! {
    #[cfg(feature = "measure")]
    {
        cortex_m_semihosting::hprintln!("configuration refused");
        cortex_m_semihosting::debug::exit(cortex_m_semihosting::debug::EXIT_FAILURE);
    }
    loop {
        cortex_m::asm::nop();
    }
}

/// The panic handlers of a no-panic probe (`*_no_panic` firmware). In the build whose flash is
/// measured, the handler calls a function that is declared but defined nowhere, so the probe
/// links only if no panic path survives optimisation in what it calls; the measuring build
/// (feature `measure`) stops with [`refused`] instead, so it can run under QEMU.
#[macro_export]
macro_rules! no_panic_probe {
    () => {
        #[cfg(not(feature = "measure"))]
        mod no_panic {
            unsafe extern "Rust" {
                /// Defined nowhere: a call to it that survives optimisation fails the link.
                fn a_panic_path_is_left() -> !;
            }

            #[panic_handler]
            fn panic(_: &core::panic::PanicInfo) -> ! {
                unsafe { a_panic_path_is_left() }
            }
        }

        #[cfg(feature = "measure")]
        #[panic_handler]
        fn panic(_: &core::panic::PanicInfo) -> ! {
            $crate::refused()
        }
    };
}

/// What a probe's inputs are: words read at run time, so the compiler must allow for any value.
/// A probe keeps its own `static mut` table and reads it through [`at`], index taken modulo the
/// table's length (the index itself may come from run time).
pub fn at<T: Copy, const N: usize>(table: &'static [T; N], i: usize) -> T {
    // A volatile read of an element of a static array, the index in range.
    let i = if N == 0 { 0 } else { i % N };
    unsafe { core::ptr::read_volatile(table.as_ptr().add(i)) }
}

/// Writes `value` where the compiler must assume it is read (so nothing computed is dropped).
pub fn keep(value: u32) {
    static mut SINK: u32 = 0;
    unsafe { core::ptr::write_volatile(&raw mut SINK, value) };
}

/// A hash of what `value`'s `Display` writes, so a probe runs the formatting code an operator's
/// screen would.
pub fn shown(value: &impl core::fmt::Display) -> u32 {
    struct Count(u32);
    impl core::fmt::Write for Count {
        fn write_str(&mut self, s: &str) -> core::fmt::Result {
            for b in s.bytes() {
                self.0 = self.0.wrapping_mul(31).wrapping_add(u32::from(b));
            }
            Ok(())
        }
    }
    let mut count = Count(0);
    let _ = core::fmt::write(&mut count, format_args!("{value}"));
    keep(count.0);
    count.0
}

#[cfg(feature = "measure")]
mod measure {
    // The stack is raw memory between two linker symbols: reading and repainting it needs raw
    // pointers. This is measuring firmware, not a library; nothing else here is unsafe.
    unsafe extern "C" {
        static _stack_end: u32;
    }

    const PAINT: u32 = 0xcccc_cccc;
    /// Words left unpainted just below this function's stack pointer, for anything it pushes
    /// itself before the call; a figure below 16 bytes reads as 16.
    const MARGIN_WORDS: usize = 4;

    /// The measured call in a frame of its own: inlined into `stack`, its locals would sit in
    /// `stack`'s frame, above the stack pointer read there, and go unseen.
    #[inline(never)]
    fn call<R>(f: impl FnOnce() -> R) -> R {
        f()
    }

    #[inline(never)]
    pub(crate) fn stack<R>(name: &str, f: impl FnOnce() -> R) -> R {
        let bottom = core::ptr::addr_of!(_stack_end) as usize;
        let sp = cortex_m::register::msp::read() as usize;
        let top = sp - MARGIN_WORDS * 4;
        let mut p = bottom;
        while p < top {
            unsafe { core::ptr::write_volatile(p as *mut u32, PAINT) };
            p += 4;
        }
        let result = call(f);
        let mut lowest = bottom;
        while lowest < top && unsafe { core::ptr::read_volatile(lowest as *const u32) } == PAINT {
            lowest += 4;
        }
        // Depth below the caller's stack pointer; the margin is counted as used only if touched.
        let used = sp.saturating_sub(lowest);
        cortex_m_semihosting::hprintln!("stack {} {}", name, used);
        result
    }
}
