//! Start-up after a restart: the tracker and the stretch meter brought back from what was stored.

use crate::stretch::{StretchConfig, StretchConfigError, StretchMeter};
use crate::tracker::{Snapshot, Tracker};

/// What [`start_up`] found usable, and so whose DIA the tracker and the meter now share.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum StartUp {
    /// Snapshot restored and meter loaded: the meter took the table's DIA (the trolleys on the
    /// chain were scaled with it).
    Both,
    /// The snapshot was missing or refused (the trolleys on the chain are lost), the meter was
    /// loaded: the cleared tracker was recalibrated to the meter's DIA.
    MeterOnly,
    /// Snapshot restored, no meter: a new meter starts from the table's DIA.
    SnapshotOnly,
    /// Neither usable (or the stored meter's DIA gives this table no valid distances): the
    /// tracker is cleared at the DIA it was built with, the meter starts from it.
    Neither,
}

/// Brings a tracker and its stretch meter back after a restart, from what was stored.
///
/// `tracker` is built from the configuration; `snapshot` is the stored [`Snapshot`] (`None`
/// when there is none or it could not be read), `meter` the stored [`StretchMeter`] (`None` when
/// there is none or it did not deserialize), `config` the meter's configuration, used when a new
/// meter must be made. Returns the meter to run with and what was usable:
///
/// - both: the snapshot is restored and the meter [reconciled](StretchMeter::reconcile) with the
///   table, whose DIA the trolleys on the chain were scaled with;
/// - the meter only (snapshot missing or refused, e.g. torn by the power failure): the tracker is
///   cleared (send what arrives to the reject path) and
///   [recalibrated](Tracker::recalibrate) to the meter's DIA — the meter's is the measured chain,
///   the table's would be SIA;
/// - the snapshot only: a new meter starts from the table's DIA;
/// - neither: the tracker is cleared at the DIA it was built with (SIA) and a new meter starts
///   from it. The chain's DIA is then unknown: a chain stretched more than
///   `plausible_per_mille` from SIA is measured [`Implausible`](crate::Measurement::Implausible)
///   (counted in [`StretchMeter::rejected`]) until an operator enters its DIA
///   ([`StretchMeter::with_dia`] and `recalibrate`).
///
/// Afterwards, power having failed at any step of a measurement cycle (between a measurement, the
/// `recalibrate` it asked for, storing the meter and storing the snapshot), the next
/// `confirmations` measurements of the chain bring meter and table to the DIA they would have
/// had without the power failure (in the last case, for a chain within the band around SIA).
///
/// An error only when a new meter must be made and `config` is refused.
pub fn start_up<K: Copy, const N: usize, const T: usize>(
    tracker: &mut Tracker<K, N, T>,
    snapshot: Option<&Snapshot<K, N, T>>,
    meter: Option<StretchMeter>,
    config: StretchConfig,
) -> Result<(StretchMeter, StartUp), StretchConfigError> {
    let restored = snapshot.is_some_and(|s| tracker.restore(s).is_ok());
    if !restored {
        tracker.clear();
    }
    match (meter, restored) {
        (Some(mut meter), true) => {
            meter.reconcile(tracker.table().dia())?;
            Ok((meter, StartUp::Both))
        }
        (Some(mut meter), false) => {
            // An empty tracker takes any DIA its table can be scaled to.
            if tracker.recalibrate(meter.dia()).is_ok() {
                Ok((meter, StartUp::MeterOnly))
            } else {
                meter.reconcile(tracker.table().dia())?;
                Ok((meter, StartUp::Neither))
            }
        }
        (None, true) => Ok((
            StretchMeter::with_dia(config, tracker.table().dia())?,
            StartUp::SnapshotOnly,
        )),
        (None, false) => Ok((
            StretchMeter::with_dia(config, tracker.table().dia())?,
            StartUp::Neither,
        )),
    }
}
