//! The operator layer at the level the operator meets it: edits, commits and samples of a
//! [`Station`], against simple models of what the README and module docs promise.

use regler_pid::{Code, Config, Kind, OperatorLimits, Parameters, Scaling, Station};

#[derive(Clone, Copy, Debug, PartialEq)]
enum Op {
    EditKp,
    EditTi,
    Commit,
    Sample,
    Discard,
}

const OPS: [Op; 5] = [Op::EditKp, Op::EditTi, Op::Commit, Op::Sample, Op::Discard];

/// The promise: a sample puts into force the set exactly as it was at the last commit before
/// it (edits keyed after that commit wait for their own commit); discard throws away the edits
/// not yet committed.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Model {
    shadow: (f64, f64),
    pending: Option<(f64, f64)>,
    active: (f64, f64),
}

/// Every interleaving of up to six edits, commits, discards and samples.
#[test]
fn a_commit_puts_into_force_the_set_as_it_was_when_committed() {
    let params = Parameters {
        config: Config::default(),
        setpoint: 50.0,
        rfel: 5.0,
        night_setback: 0.0,
    };
    let scaling = Scaling::new(0.0, 100.0).unwrap();
    let start = (params.config.k, params.config.ti);
    let mut checked = 0u32;
    for len in 1..=6u32 {
        for mut n in 0..5usize.pow(len) {
            let mut st = Station::<f64>::new(params, scaling, OperatorLimits::default()).unwrap();
            let mut model = Model {
                shadow: start,
                pending: None,
                active: start,
            };
            let mut trace = Vec::new();
            for step in 0..len {
                let op = OPS[n % 5];
                n /= 5;
                trace.push(op);
                let value = f64::from(step) + 1.0;
                match op {
                    Op::EditKp => {
                        st.staged_mut().edit(Code::Kp, value).unwrap();
                        model.shadow.0 = value;
                    }
                    Op::EditTi => {
                        st.staged_mut().edit(Code::Ti, value).unwrap();
                        model.shadow.1 = value;
                    }
                    Op::Commit => {
                        st.staged_mut().commit();
                        model.pending = Some(model.shadow);
                    }
                    Op::Sample => {
                        st.sample(49.0);
                        if let Some(p) = model.pending.take() {
                            model.active = p;
                        }
                    }
                    Op::Discard => {
                        st.staged_mut().discard();
                        model.shadow = model.pending.unwrap_or(model.active);
                    }
                }
                let got_active = (st.value(Code::Kp).unwrap(), st.value(Code::Ti).unwrap());
                let got_shadow = (
                    st.staged().shadow_value(Code::Kp).unwrap(),
                    st.staged().shadow_value(Code::Ti).unwrap(),
                );
                assert_eq!(got_active, model.active, "{trace:?}: in force");
                assert_eq!(got_shadow, model.shadow, "{trace:?}: shadow");
                assert_eq!(
                    st.staged().commit_pending(),
                    model.pending.is_some(),
                    "{trace:?}"
                );
                assert_eq!(
                    st.staged()
                        .pending()
                        .copied()
                        .map(|p| (p.config.k, p.config.ti)),
                    model.pending,
                    "{trace:?}"
                );
                checked += 1;
            }
        }
    }
    assert!(checked > 90_000);
}
