//! regler-trolley-id on the core.

use regler_trolley_id::{
    AlarmChange, AlarmLimits, NoRead, ReadError, ReaderHealth, Registry, Route, Strategy,
    TrolleyId, Verdict, Voter, decode, encode,
};

use crate::{Outcome, check};

pub fn decode_all_8192_words() -> Outcome {
    let mut valid = 0u32;
    for raw in 0u16..8192 {
        match decode(raw) {
            Ok(id) => {
                valid += 1;
                check!(encode(id) == raw);
                check!((raw & 0x1FFF).count_ones() % 2 == 0);
            }
            Err(ReadError::NoCams) => check!(raw == 0),
            Err(ReadError::Parity { .. }) => check!(raw.count_ones() % 2 == 1),
            Err(_) => return Err("unexpected error kind for a 13-bit word"),
        }
    }
    check!(valid == 4095);
    check!(decode(0x2000).is_err());
    Ok(())
}

pub fn voters_never_invent_a_trolley() -> Outcome {
    let id = |n| TrolleyId::new(n).ok_or("id");
    let reads = [encode(id(51)?), encode(id(15)?), encode(id(60)?)];
    let mut majority = Voter::new(Strategy::Majority { min_samples: 3 }).map_err(|_| "voter")?;
    check!(
        majority.vote(&reads).verdict == Verdict::NoRead(NoRead::Unsupported { majority: id(63)? })
    );
    let a = encode(id(1234)?);
    check!(majority.vote(&[a, a ^ 0b11, a, 0]).verdict == Verdict::Identified(id(1234)?));
    let mut consecutive = Voter::new(Strategy::Consecutive { k: 2 }).map_err(|_| "voter")?;
    check!(consecutive.vote(&[a, a]).verdict == Verdict::Identified(id(1234)?));
    check!(matches!(
        consecutive.vote(&reads).verdict,
        Verdict::NoRead(_)
    ));
    Ok(())
}

pub fn registry_routes() -> Outcome {
    // One cell per trolley number: 4096 one-byte cells here, on a 16 KiB core.
    let mut reg: Registry<bool> = Registry::new();
    let t = TrolleyId::new(77).ok_or("id")?;
    reg.assign(t, true);
    check!(matches!(
        reg.route(&Verdict::Identified(t), |d| *d),
        Route::Deliver {
            destination: true,
            ..
        }
    ));
    check!(matches!(
        reg.route(&Verdict::Identified(t), |d| !*d),
        Route::Reject(_)
    ));
    let other = TrolleyId::new(78).ok_or("id")?;
    check!(matches!(
        reg.route(&Verdict::Identified(other), |_| true),
        Route::Reject(_)
    ));
    check!(reg.len() == 1);
    Ok(())
}

pub fn reader_health_alarm() -> Outcome {
    let limits = AlarmLimits {
        no_read_per_mille: 100,
        disagreement_per_mille: 1000,
        min_passages: 10,
    };
    let mut health: ReaderHealth<50> = ReaderHealth::new(limits).map_err(|_| "limits")?;
    let mut voter = Voter::new(Strategy::Consecutive { k: 2 }).map_err(|_| "voter")?;
    let good = encode(TrolleyId::new(7).ok_or("id")?);
    for _ in 0..9 {
        check!(health.record(&voter.vote(&[good, good])).is_none());
    }
    health.record(&voter.vote(&[0x0001]));
    check!(health.record(&voter.vote(&[0x0001])) == Some(AlarmChange::Raised));
    check!(health.alarm());
    Ok(())
}
