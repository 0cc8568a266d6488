//! Which robot each link of a recording is, for exports that write one output per robot:
//! the names of their CSV files and the prefixes of their MCAP topics.
//!
//! Layer: pure, over a parsed `Recording`. The rule (docs/recordings.md, "Export"): a link whose robot
//! stated an id that no other link of the file states is `robot<ID>`; any other link (never
//! connected, recorded before robots had ids, or sharing its id) is `link<K>`, K its link id
//! + 1 (the order of `--port`). A file of one link has no label: today's names. Cannot fail.

use std::path::{Path, PathBuf};

use crate::link::robot_ids::duplicates;
use crate::record::live::PeerRecord;
use crate::record::{LinkState, RecordKind, Recording};

/// The id the robot of a one-link recording stated at its last handshake.
pub fn robot_id(rec: &Recording) -> Option<u8> {
    rec.records
        .iter()
        .rev()
        .filter(|r| r.kind == RecordKind::Link)
        .filter_map(|r| r.link())
        .find(|(state, _)| *state == LinkState::Connected)
        .and_then(|(_, text)| serde_json::from_str::<PeerRecord>(&text).ok())
        .and_then(|p| p.robot_id)
}

/// The label of each link (`links` are the file's links, by link id).
pub fn labels(links: &[Recording]) -> Vec<String> {
    if links.len() < 2 {
        return vec![String::new(); links.len()];
    }
    let ids: Vec<Option<u8>> = links.iter().map(robot_id).collect();
    let ports: Vec<String> = (0..links.len()).map(|k| k.to_string()).collect();
    let shared: Vec<u8> = duplicates(ports.iter().map(String::as_str).zip(ids.iter().copied()))
        .into_iter()
        .map(|d| d.robot_id)
        .collect();
    ids.iter()
        .enumerate()
        .map(|(k, id)| match id {
            Some(id) if !shared.contains(id) => format!("robot{id}"),
            _ => format!("link{}", k + 1),
        })
        .collect()
}

/// The CSV file of the robot labelled `label`: `run.csv` -> `run.robot1.csv` (the label
/// before the extension, or at the end without one); `out` itself for an empty label.
pub fn csv_path(out: &Path, label: &str) -> PathBuf {
    if label.is_empty() {
        return out.to_path_buf();
    }
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let name = match out.extension() {
        Some(ext) => format!("{stem}.{label}.{}", ext.to_string_lossy()),
        None => format!("{stem}.{label}"),
    };
    out.with_file_name(name)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::synth::{demo, merge, Synth};
    use crate::record::Meta;

    fn robot(id: u8) -> Vec<u8> {
        let mut s = Synth::new(&Meta::default());
        let mut peer = crate::record::synth::demo_peer();
        peer.robot_id = id;
        s.handshake(peer);
        s.finish(1_000_000, "done")
    }

    #[test]
    fn unique_ids_name_robots_and_the_rest_are_named_by_link() {
        let rec = |parts: &[Vec<u8>]| Recording::parse_strict(&merge(parts, "d")).unwrap().links();
        assert_eq!(labels(&rec(&[robot(1), robot(2)])), ["robot1", "robot2"]);
        assert_eq!(
            labels(&rec(&[robot(7), robot(7), robot(3)])),
            ["link1", "link2", "robot3"]
        );
        let never = Synth::new(&Meta::default()).finish(5, "d");
        assert_eq!(labels(&rec(&[never, robot(2)])), ["link1", "robot2"]);
        assert_eq!(
            labels(&Recording::parse_strict(&demo(1, 10)).unwrap().links()),
            [""]
        );
    }

    #[test]
    fn csv_names_put_the_label_before_the_extension() {
        assert_eq!(
            csv_path(Path::new("out/run.csv"), "robot2"),
            Path::new("out/run.robot2.csv")
        );
        assert_eq!(csv_path(Path::new("run"), "link1"), Path::new("run.link1"));
        assert_eq!(csv_path(Path::new("run.csv"), ""), Path::new("run.csv"));
    }
}
