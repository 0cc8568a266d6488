//! The object parsers (PROTOCOL.md §12) on arbitrary bytes: what a Map, Plan or light
//! calibration file given to `station upload-map` / `upload-plan` / `upload-calibration` or a
//! downloaded object goes through. Invariants: no
//! panic; `kind_of` and `parse` agree on the kind of whatever `parse` accepts; an accepted
//! Map or Plan re-parses through its own view, and walking every cell or waypoint stays in
//! bounds.
#![no_main]

use libfuzzer_sys::fuzz_target;
use protocol::object::{
    encode_light, kind_of, parse, MapView, ObjectView, PlanView, LIGHT_MAX_OUTPUT,
    LIGHT_NEURONS, LIGHT_OBJECT_LEN,
};

fuzz_target!(|data: &[u8]| {
    let kind = kind_of(data);
    let Ok(view) = parse(data) else { return };
    let kind = kind.expect("parse accepted what kind_of refused");
    match view {
        ObjectView::Map(m) => {
            assert_eq!(kind, protocol::ObjectKind::Map);
            let again = MapView::parse(data).expect("a parsed map re-parses");
            assert_eq!(again.header, m.header);
            let (w, h) = (m.header.width, m.header.height);
            if u32::from(w) * u32::from(h) <= 1 << 16 {
                for y in 0..h {
                    for x in 0..w {
                        assert!(m.cell(x, y).is_some_and(|c| c <= 3));
                    }
                }
            }
            assert_eq!(m.cell(w, 0), None);
        }
        ObjectView::Plan(p) => {
            assert_eq!(kind, protocol::ObjectKind::Plan);
            let again = PlanView::parse(data).expect("a parsed plan re-parses");
            assert_eq!(again.waypoint_count(), p.waypoint_count());
            assert_eq!(p.waypoints().count(), usize::from(p.waypoint_count()));
            let _ = p.meta;
        }
        ObjectView::Regions(_) => assert_eq!(kind, protocol::ObjectKind::Regions),
        ObjectView::LightCalibration(l) => {
            assert_eq!(kind, protocol::ObjectKind::LightCalibration);
            // Every neuron reads back within the bound the parser checked; re-encoding
            // gives the very bytes (the encoding is canonical).
            let neurons: Vec<_> = l.neurons().collect();
            assert_eq!(neurons.len(), LIGHT_NEURONS);
            assert!(neurons.iter().all(|(_, o)| *o <= LIGHT_MAX_OUTPUT));
            let mut out = vec![0; LIGHT_OBJECT_LEN];
            let n = encode_light(neurons, &mut out).expect("a parsed network re-encodes");
            assert_eq!(&out[..n], data);
        }
    }
});
