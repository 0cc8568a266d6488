//! The summary of a recording of several links: one `Summary` per link, and the robot ids
//! that two links share.
//!
//! Layer: pure, over a parsed `Recording`. Each link is summarised as a recording of its own
//! (`Recording::link`), so a link's numbers are exactly what a one-link recording of it would
//! give. A one-link file keeps today's summary (`summary::summarize`): `station replay --json`
//! prints this only for files of several links. Cannot fail.

use serde::Serialize;

use super::summary::{self, Damage, Summary};
use crate::link::robot_ids::{duplicates, DuplicateId};
use crate::record::Recording;

/// One link of a fleet recording.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LinkSummary {
    /// The link id in the file (0-based, the order of `--port`).
    pub link: u8,
    pub port: String,
    /// The id its robot stated at its last handshake (none: never connected, or recorded
    /// before robots had ids).
    pub robot_id: Option<u8>,
    pub summary: Summary,
}

/// Everything `station replay --json` prints for a file of several links.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FleetSummary {
    pub format_version: u16,
    pub file_bytes: u64,
    pub records: usize,
    pub duration_s: f64,
    pub end: Option<String>,
    pub damage: Option<Damage>,
    pub links: Vec<LinkSummary>,
    /// Robot ids stated on more than one link.
    pub duplicate_robot_ids: Vec<DuplicateId>,
}

/// Summarises every link of `rec`.
pub fn summarize_links(rec: &Recording) -> FleetSummary {
    let links: Vec<LinkSummary> = rec
        .links()
        .iter()
        .enumerate()
        .map(|(i, one)| {
            let s = summary::summarize(one);
            LinkSummary {
                link: u8::try_from(i).unwrap_or(u8::MAX),
                port: one.meta.port.clone(),
                robot_id: s.robot.as_ref().and_then(|r| r.robot_id),
                summary: s,
            }
        })
        .collect();
    let duplicate_robot_ids = duplicates(links.iter().map(|l| (l.port.as_str(), l.robot_id)));
    FleetSummary {
        format_version: rec.version,
        file_bytes: rec.file_len,
        records: rec.records.len(),
        duration_s: rec.duration_us() as f64 / 1e6,
        end: rec.end.clone(),
        damage: rec.damage.as_ref().map(|d| Damage {
            offset: d.offset(),
            error: d.to_string(),
        }),
        links,
        duplicate_robot_ids,
    }
}

/// The fleet summary as text: one section per link (the one-link text), then the warnings.
pub fn text(file: &str, s: &FleetSummary) -> String {
    let mut out = format!(
        "{file}: {} links, {:.1} s, {} records\n",
        s.links.len(),
        s.duration_s,
        s.records
    );
    for l in &s.links {
        out.push_str(&format!(
            "\n== link {} ({}), robot id {}\n",
            l.link,
            l.port,
            l.robot_id
                .map_or("unknown".to_string(), |id| id.to_string())
        ));
        out.push_str(&summary::text(file, &l.summary));
    }
    for d in &s.duplicate_robot_ids {
        out.push_str(&format!("\nWARNING     {}\n", d.warning()));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::synth::{demo, merge};

    #[test]
    fn each_link_is_summarised_as_its_own_recording() {
        let one = demo(2, 10);
        let fleet = Recording::parse_strict(&merge(&[one.clone(), demo(3, 10)], "done")).unwrap();
        let s = summarize_links(&fleet);
        assert_eq!(s.format_version, 2);
        assert_eq!(s.links.len(), 2);
        let alone = summary::summarize(&Recording::parse_strict(&one).unwrap());
        assert_eq!(s.links[0].summary.telemetry.frames, alone.telemetry.frames);
        assert_eq!(
            s.links[0].summary.frames_from_robot,
            alone.frames_from_robot
        );
        assert!(s.links[1].summary.telemetry.frames > alone.telemetry.frames);
        // Both demo robots are robot 1: reported.
        assert_eq!(s.links[0].robot_id, Some(1));
        assert_eq!(s.duplicate_robot_ids.len(), 1);
        assert!(text("f.rec", &s).contains("WARNING     robot id 1 is stated by"));
    }
}
