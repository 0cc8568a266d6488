//! Robot ids across links: which robot each link reached, and two links that reached robots
//! giving the same id.
//!
//! Layer: pure. A robot states its id (parameter `robot_id`, like MAVLink's system id) in its
//! `HelloReply`; the link reports it in `PeerInfo::robot_id`. Every place that shows several
//! links (`station stats`, `station record`, the replay summary, the fleet TUI) asks here
//! whether two of them claim one id, so the warning reads the same everywhere. Cannot fail.

use serde::Serialize;

/// Robots on several links that state the same id.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct DuplicateId {
    pub robot_id: u8,
    /// The links (their ports or labels) whose robots state it, in link order.
    pub links: Vec<String>,
}

impl DuplicateId {
    /// The warning for a person: what is wrong and how to mend it.
    pub fn warning(&self) -> String {
        format!(
            "robot id {} is stated by the robots on {}: commands and recordings cannot tell \
             them apart; give each its own (`station params --port PORT set robot_id N`)",
            self.robot_id,
            self.links.join(" and ")
        )
    }
}

/// The ids stated by more than one link. `links` is each link's label and its robot's id
/// (`None`: no robot has answered on it yet, which clashes with nothing).
pub fn duplicates<'a>(links: impl IntoIterator<Item = (&'a str, Option<u8>)>) -> Vec<DuplicateId> {
    let mut by_id: std::collections::BTreeMap<u8, Vec<String>> = Default::default();
    for (label, id) in links {
        if let Some(id) = id {
            by_id.entry(id).or_default().push(label.to_string());
        }
    }
    by_id
        .into_iter()
        .filter(|(_, l)| l.len() > 1)
        .map(|(robot_id, links)| DuplicateId { robot_id, links })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_ids_stated_twice_are_reported_with_every_link() {
        let d = duplicates([
            ("/tmp/robot1", Some(1)),
            ("/tmp/robot2", Some(2)),
            ("/tmp/robot3", Some(1)),
            ("/tmp/robot4", None),
        ]);
        assert_eq!(
            d,
            vec![DuplicateId {
                robot_id: 1,
                links: vec!["/tmp/robot1".into(), "/tmp/robot3".into()],
            }]
        );
        let w = d[0].warning();
        assert!(
            w.contains("robot id 1 is stated by the robots on /tmp/robot1 and /tmp/robot3"),
            "{w}"
        );
        assert!(duplicates([("a", Some(1)), ("b", Some(2)), ("c", None), ("d", None)]).is_empty());
    }
}
