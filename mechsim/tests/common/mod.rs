//! What the mechanism tests share.

use propid_mechsim::Record;

/// The records with a held force (a load cell slower than the rows repeats each reading until
/// the next) read as a user reads such a log: each reading at the row that first shows it,
/// linear in between. A stretch without a new reading for over 50 ms is left as it is.
pub fn readings_at_first_row(recs: &[Record]) -> Vec<Record> {
    let mut out = recs.to_vec();
    let mut knot: Option<usize> = None;
    for i in 1..recs.len() {
        if recs[i].force == recs[i - 1].force {
            continue;
        }
        if let Some(k) = knot {
            let span = recs[i].t - recs[k].t;
            if span > 0.0 && span <= 0.05 {
                for j in k + 1..i {
                    let w = (recs[j].t - recs[k].t) / span;
                    out[j].force = recs[k].force + w * (recs[i].force - recs[k].force);
                }
            }
        }
        knot = Some(i);
    }
    out
}
