//! A probe, not a measurement: firmware whose panic handler calls a function that is declared
//! but defined nowhere, so it links only if no panic path is left in what it calls — the
//! calendar (`DateTime::new`, `advance` over every size of step, `MinuteTable::add`, `check`,
//! `due`, `set_checked_up_to`), input conditioning (`set_debounce`, `set_latched`, `capture`,
//! `condition`, on points read at run time) and the timer shift register (`insert`, `tick`,
//! `remaining`, `replace`, `remove` with delays read at run time), and the `Display` of `DateTime`
//! and of every error here. The measuring build (feature
//! `measure`) runs the calls under QEMU with an ordinary panic handler.
#![no_std]
#![no_main]

use core::hint::black_box;
use core::ptr::{addr_of, read_volatile, write_volatile};

use cortex_m_rt::entry;
use regler_footprint::{MEASURING, finish, shown};
use regler_scan_cycle::{Conditioning, DateTime, Image, MinuteTable, Start, TimerQueue, Weekdays};

static FIELDS: [u16; 6] = [9999, 12, 31, 23, 58, 30];
static STEPS: [u32; 5] = [u32::MAX, 0, 60_000, 150_000, 1];
static LINES: [(u8, u8, u8); 4] = [(6, 0, 0x7F), (23, 59, 0xFF), (0, 0, 0), (12, 30, 0x1F)];
static RAW: [u16; 3] = [0xFFFF, 0x00F0, 0x1234];
static POINT: usize = 17;
static COUNT: u8 = 7;
static DELAYS: [u32; 3] = [u32::MAX, 0, 1];
static mut OUT: u64 = 0;

fn field(i: usize) -> u8 {
    let f = unsafe { read_volatile(addr_of!(FIELDS)) };
    f.get(i).map_or(0, |&v| v as u8)
}

#[entry]
fn main() -> ! {
    let mut acc = 0u64;
    let year = unsafe { read_volatile(addr_of!(FIELDS)) }[0];
    let mut clock = DateTime::new(year, field(1), field(2), field(3), field(4), field(5))
        .unwrap_or_else(|e| {
            acc ^= u64::from(shown(&e));
            DateTime::END
        });
    let mut table: MinuteTable<u8, 8> = MinuteTable::new();
    for (i, &(hour, minute, days)) in unsafe { read_volatile(addr_of!(LINES)) }.iter().enumerate() {
        if let Err(e) = table.add(Start {
            hour,
            minute,
            days: Weekdays(days),
            program: i as u8,
        }) {
            acc ^= u64::from(shown(&e));
        }
    }
    for &step in unsafe { read_volatile(addr_of!(STEPS)) }.iter() {
        acc = acc.wrapping_add(u64::from(clock.advance(black_box(step))));
        let checked = table.check(&clock, |due| {
            acc = acc
                .wrapping_add(u64::from(*due.program))
                .wrapping_add(due.minutes_late ^ due.missed);
        });
        acc = acc.wrapping_add(checked.missed ^ checked.behind_minutes);
        acc = acc.wrapping_add(u64::from(clock.weekday()) + u64::from(clock.iso_week()));
        acc ^= u64::from(shown(&clock));
        for program in table.due(&clock) {
            acc = acc.wrapping_add(u64::from(*program));
        }
    }
    table.set_checked_up_to(black_box(Some(clock)));

    let mut conditioning: Conditioning<3> = Conditioning::new();
    let point = unsafe { read_volatile(addr_of!(POINT)) };
    let count = unsafe { read_volatile(addr_of!(COUNT)) };
    acc ^= u64::from(conditioning.set_debounce(point, count).is_ok());
    acc ^= u64::from(
        conditioning
            .set_latched(black_box(point.wrapping_add(1)), true)
            .is_ok(),
    ) << 1;
    acc ^= u64::from(
        conditioning
            .set_latched(black_box(point.wrapping_add(1)), false)
            .is_ok(),
    ) << 2;
    let raw = unsafe { read_volatile(addr_of!(RAW)) };
    let mut image = Image::<3>::new();
    for _ in 0..black_box(20) {
        conditioning.capture(&raw);
        conditioning.condition(&raw, &mut image);
        acc ^= u64::from(image.word(black_box(1)).unwrap_or(0));
    }

    let mut queue: TimerQueue<u32, 16> = TimerQueue::new();
    let mut ids = [None; 3];
    for (slot, &delay) in ids
        .iter_mut()
        .zip(unsafe { read_volatile(addr_of!(DELAYS)) }.iter())
    {
        *slot = queue
            .insert(delay, delay)
            .map_err(|e| acc ^= u64::from(shown(&e)))
            .ok();
    }
    for _ in 0..black_box(3) {
        queue.tick(|action| acc = acc.wrapping_add(u64::from(action)));
    }
    for id in ids.iter().flatten() {
        acc ^= u64::from(queue.remaining(*id).unwrap_or(7));
        if let Err(e) = queue.replace(*id, black_box(5)) {
            acc ^= u64::from(shown(&e));
        }
        acc ^= u64::from(queue.remove(*id).unwrap_or(9));
    }
    unsafe { write_volatile(&raw mut OUT, acc) };
    if MEASURING {
        finish();
    }
    loop {
        cortex_m::asm::nop();
    }
}

regler_footprint::no_panic_probe!();
