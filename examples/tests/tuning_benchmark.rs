//! The automatic-tuning evaluation on the benchmark processes: what each rule gives, checked
//! against the analytic ultimate points and the rules' published robustness.

use regler_examples::autonomous::benchmark::evaluate;

#[test]
fn automatic_tuning_on_the_benchmark_processes() {
    let found = evaluate();
    assert_eq!(found.len(), 8);
    for f in &found {
        let rows = |rule: &str| f.rows.iter().find(|r| r.rule.starts_with(rule));
        // The relay works on every process, and for lag chains it lands within 3 %.
        let (ku, tu) = f.ultimate.expect("relay estimate");
        let (kt, tt) = f
            .ultimate_true
            .expect("every benchmark here has an ultimate point");
        assert!(
            (tu / tt - 1.0).abs() < 0.05,
            "{}: Tu {tu} vs {tt}",
            f.process
        );
        if f.process.starts_with("1/(s+1)") {
            assert!(
                (ku / kt - 1.0).abs() < 0.03,
                "{}: Ku {ku} vs {kt}",
                f.process
            );
        }
        match &f.fopdt {
            Ok(_) => {
                // AMIGO is designed for Ms = 1.4; SIMC with tc = L gives about 1.6.
                let a = rows("AMIGO PI").expect("AMIGO PI row");
                assert!(
                    (1.15..=1.5).contains(&a.ms),
                    "{}: AMIGO PI Ms {}",
                    f.process,
                    a.ms
                );
                let a = rows("AMIGO PID").expect("AMIGO PID row");
                assert!(
                    (1.3..=1.5).contains(&a.ms),
                    "{}: AMIGO PID Ms {}",
                    f.process,
                    a.ms
                );
                let s = rows("SIMC PI").expect("SIMC row");
                assert!(
                    (1.5..=1.7).contains(&s.ms),
                    "{}: SIMC Ms {}",
                    f.process,
                    s.ms
                );
                // Ziegler–Nichols is the least robust of the three everywhere.
                let zn = rows("ZN PI").expect("ZN PI row");
                assert!(
                    zn.ms > s.ms,
                    "{}: ZN PI Ms {} vs SIMC {}",
                    f.process,
                    zn.ms,
                    s.ms
                );
            }
            Err(e) => {
                // The integrating process never settles; the inverse response first goes the
                // wrong way (2.7 % of the change), which an FOPDT model cannot represent.
                if f.process.starts_with("1/(s(") {
                    assert!(e.contains("does not settle"), "{}: {e}", f.process);
                } else {
                    assert!(f.process.starts_with("(1-"), "{}: {e}", f.process);
                    assert!(e.contains("inverse response"), "{}: {e}", f.process);
                }
            }
        }
        for r in &f.rows {
            assert!(r.iae_setpoint.is_finite() && r.iae_load.is_finite() && r.ms.is_finite());
        }
    }
    // The known failure of Ziegler–Nichols on dead time: the relay's Ku is 22 % high there and
    // the PID setting it gives is unstable.
    let dead = found.iter().find(|f| f.process == "e^-s/(1+0.1s)").unwrap();
    let zn_pid = dead
        .rows
        .iter()
        .find(|r| r.rule.starts_with("ZN PID"))
        .unwrap();
    assert!(zn_pid.ms > 5.0 && zn_pid.iae_load > 100.0, "{zn_pid:?}");
}
