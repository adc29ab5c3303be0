//! The header of a LAS input that its LAS outputs carry over, and the header fields every
//! output sets.

use las::raw::Header as RawHeader;
use las::{Header, Vlr};

/// What a LAS input's header holds beyond its points and field layout, which a LAS output
/// of its table writes again, so that the coordinate reference system and the user's records
/// survive labelling.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct InputHeader {
    /// The VLRs, except those a writer makes anew: Extra Bytes (whose descriptors are in
    /// `descriptors`), LASzip, waveform packet descriptors (waveforms are not written) and
    /// COPC (the output's points are not in COPC order).
    pub vlrs: Vec<Vlr>,
    /// The extended VLRs, except waveform data and the COPC hierarchy.
    pub evlrs: Vec<Vlr>,
    /// The global encoding bits: GPS time type (bit 0) and synthetic return numbers (bit 3)
    /// are carried over; the WKT bit follows the carried CRS records.
    pub global_encoding: u16,
    /// The file source (flight line) ID.
    pub file_source_id: u16,
    /// The project GUID.
    pub guid: [u8; 16],
    /// The Extra Bytes descriptors, 192 bytes each, in file order.
    pub(crate) descriptors: Vec<u8>,
}

/// True for the records a writer makes anew (see [`InputHeader::vlrs`]).
fn made_anew(vlr: &Vlr) -> bool {
    match (vlr.user_id.as_str(), vlr.record_id) {
        ("LASF_Spec", id) => id == 4 || (100..=354).contains(&id) || id == 65535,
        (user, _) => user == "laszip encoded" || user == "copc",
    }
}

impl InputHeader {
    /// What `header` carries over.
    pub(super) fn of(header: &Header) -> Result<Self, las::Error> {
        let raw = header.clone().into_raw()?;
        let keep = |vlrs: &[Vlr]| vlrs.iter().filter(|v| !made_anew(v)).cloned().collect();
        let descriptors = (header.all_vlrs())
            .find(|v| v.user_id == "LASF_Spec" && v.record_id == 4)
            .map(|v| v.data.clone())
            .unwrap_or_default();
        Ok(InputHeader {
            vlrs: keep(header.vlrs()),
            evlrs: keep(header.evlrs()),
            global_encoding: raw.global_encoding,
            file_source_id: raw.file_source_id,
            guid: raw.guid,
            descriptors,
        })
    }
}

/// Sets the fields of an output's `raw` header that the las crate leaves to the writer:
/// the input's GPS time type, synthetic-return bit, file source ID and GUID (with `input`),
/// the WKT bit (set unless the CRS records are GeoTIFF keys alone, which readers then look
/// for), zero legacy point counts (LAS 1.4 requires them for point formats 6 and above), the
/// creation day and year (UTC; `SOURCE_DATE_EPOCH` when set, for reproducible files) and the
/// system identifier ("MODIFICATION" of a LAS input, as the specification suggests, else
/// "OTHER").
pub(super) fn finish(raw: &mut RawHeader, input: Option<&InputHeader>, vlrs: &[&Vlr]) {
    const GPS_AND_SYNTHETIC: u16 = 0b1001;
    const WKT: u16 = 0b1_0000;
    let carried = input.map_or(0, |h| h.global_encoding & GPS_AND_SYNTHETIC);
    let projection = |ids: &[u16]| {
        (vlrs.iter()).any(|v| v.user_id == "LASF_Projection" && ids.contains(&v.record_id))
    };
    let geotiff_only = projection(&[34735]) && !projection(&[2111, 2112]);
    raw.global_encoding = carried | if geotiff_only { 0 } else { WKT };
    if let Some(input) = input {
        raw.file_source_id = input.file_source_id;
        raw.guid = input.guid;
    }
    raw.number_of_point_records = 0;
    raw.number_of_points_by_return = [0; 5];
    let (year, day) = year_and_day(now_days());
    raw.file_creation_year = year;
    raw.file_creation_day_of_year = day;
    let system = if input.is_some() {
        "MODIFICATION"
    } else {
        "OTHER"
    };
    raw.system_identifier = [0; 32];
    raw.system_identifier[..system.len()].copy_from_slice(system.as_bytes());
}

/// Days since 1970-01-01 UTC: of `SOURCE_DATE_EPOCH` (seconds) when it is set, else of now.
fn now_days() -> u64 {
    let seconds = std::env::var("SOURCE_DATE_EPOCH")
        .ok()
        .and_then(|s| s.trim().parse::<u64>().ok())
        .unwrap_or_else(|| {
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_secs())
        });
    seconds / 86_400
}

/// The year and the 1-based day of that year of `days` since 1970-01-01 (Gregorian).
fn year_and_day(mut days: u64) -> (u16, u16) {
    let mut year: u16 = 1970;
    loop {
        let leap =
            year.is_multiple_of(4) && (!year.is_multiple_of(100) || year.is_multiple_of(400));
        let length = if leap { 366 } else { 365 };
        if days < length || year == u16::MAX {
            return (year, days as u16 + 1);
        }
        days -= length;
        year += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn days_since_1970_become_year_and_day_of_year() {
        assert_eq!(year_and_day(0), (1970, 1));
        assert_eq!(year_and_day(364), (1970, 365));
        assert_eq!(year_and_day(365), (1971, 1));
        // 2000-02-29 is day 11016 (951782400 s), the 60th day of a leap year that is a
        // multiple of 400; 2100-03-01 (4107542400 s) is the 60th of a non-leap century year.
        assert_eq!(year_and_day(951_782_400 / 86_400), (2000, 60));
        assert_eq!(year_and_day(4_107_542_400 / 86_400), (2100, 60));
        // 2026-12-01: 20788 days.
        assert_eq!(year_and_day(20_788), (2026, 335));
    }
}
