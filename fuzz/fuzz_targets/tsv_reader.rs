//! Fuzz the TSV reader: any bytes must give rows or an error, never a panic; a row read is
//! written back (with the stand columns the file has) and read again to the same values (bit for bit, NaN as NaN).
#![no_main]

use libfuzzer_sys::fuzz_target;
use propid_io::tsv::{TsvReader, TsvWriter};

fuzz_target!(|bytes: &[u8]| {
    let Ok(mut reader) = TsvReader::new(bytes, "fuzz.tsv") else {
        return;
    };
    let mut rows = Vec::new();
    while let Ok(Some(row)) = reader.next_row() {
        rows.push(row);
        if rows.len() > 10_000 {
            break;
        }
    }
    let columns = reader.stand_columns();
    let mut writer = TsvWriter::with_columns(Vec::new(), false, &columns, &[]).unwrap();
    for r in &rows {
        writer.write(r).unwrap();
    }
    let text = writer.into_inner().unwrap();
    let mut again = TsvReader::new(&text[..], "again.tsv").unwrap();
    for r in &rows {
        let back = again.next_row().unwrap().expect("as many rows back");
        let same = |a: f64, b: f64| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
        let (a, b) = (&r.sample, &back.sample);
        assert!(same(r.ts_local, back.ts_local));
        assert!(same(a.t, b.t) && same(a.force, b.force) && same(a.velocity, b.velocity));
        assert!(same(a.acceleration, b.acceleration) && same(a.position, b.position));
        for c in &columns {
            assert!(same(r.stand.get(*c), back.stand.get(*c)));
        }
    }
    assert!(again.next_row().unwrap().is_none());
});
