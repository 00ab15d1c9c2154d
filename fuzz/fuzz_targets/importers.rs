//! Fuzz the importers (RCbenchmark/Tyto and ESC32 CSV): any bytes give an import or an error
//! naming the input, never a panic; an import has strictly increasing time, one value per row in every extra column,
//! and its TSV is written.
#![no_main]

use libfuzzer_sys::fuzz_target;
use propid_io::import::{read_autoquad, read_rcbench, write_tsv, Imported, RcbenchOptions};

fn check(result: Result<Imported, propid_io::InputError>) {
    match result {
        Ok(im) => {
            assert!(im.rows.windows(2).all(|w| w[1].sample.t > w[0].sample.t));
            for c in &im.extra {
                assert_eq!(c.values.len(), im.rows.len());
            }
            write_tsv(&im, std::io::sink()).unwrap();
        }
        // Every error names the input, except a bad kv (a flag, not the file).
        Err(e) => assert!(
            e.place.file.as_deref() == Some("fuzz.csv") || e.to_string().contains("kv"),
            "{e}"
        ),
    }
}

fuzz_target!(|bytes: &[u8]| {
    // The first byte picks the importer and its options; the rest is the file.
    let Some((&which, csv)) = bytes.split_first() else {
        return;
    };
    let options = RcbenchOptions {
        subtract_zero_offset: which & 1 != 0,
        despike: which & 2 != 0,
    };
    match which % 3 {
        0 | 1 => check(read_rcbench(csv, "fuzz.csv", &options)),
        _ => check(read_autoquad(csv, "fuzz.csv", 1600.0)),
    }
});
