//! The animations a scene plays: one or several of the file's, on one clock. Files converted
//! from other tools often split one motion into an animation per joint or per node, and a
//! scene may hold a character's walk beside a door's swing; played together, their channels
//! pose the scene as one animation's would. Two of them must not drive the same property of
//! the same node, which glTF forbids within one animation: which would set it is undefined.

use super::Scene;
use super::animation::{Animation, Track};

/// The animations that frames play, and their tracks together.
#[derive(Debug, Clone, PartialEq)]
pub struct Playing {
    /// Indices into the scene's `animations`, in the order they were picked.
    pub animations: Vec<usize>,
    /// Every track of every playing animation, in that order.
    pub tracks: Vec<Track>,
    /// How messages name each track: `channels[2]` where one animation plays,
    /// `animations[1] ("wave") channels[2]` where several do.
    pub channel_names: Vec<String>,
    /// How messages name what plays: `animations[1] ("wave")`, or the several joined.
    pub label: String,
    /// How a record names it: the animation's name (`animations[1]` where it has none), or
    /// the several joined with ` + ` (`walk.0 and 18 more` past three).
    pub short_label: String,
}

impl Playing {
    /// The time of the first keyframe of any track, in seconds (0 for none).
    pub fn start(&self) -> f64 {
        first_key(&self.tracks)
    }

    /// The time of the last keyframe of any track, in seconds.
    pub fn duration(&self) -> f64 {
        last_key(&self.tracks)
    }
}

/// The time of the first keyframe of `tracks`, in seconds: before it every track holds its
/// first value (0 for no tracks).
fn first_key(tracks: &[Track]) -> f64 {
    let first =
        tracks.iter().filter_map(|t| t.times.first()).fold(f64::INFINITY, |a, &b| a.min(f64::from(b)));
    if first.is_finite() { first } else { 0.0 }
}

/// The time of the last keyframe of `tracks`, in seconds (0 for no tracks).
fn last_key(tracks: &[Track]) -> f64 {
    tracks.iter().filter_map(|t| t.times.last()).fold(0.0, |a, &b| a.max(f64::from(b)))
}

impl Scene {
    /// Plays `animations` (indices into [`Scene::animations`]) together, from the next pose on.
    /// Refused, leaving what played before, for an index the file lacks, one that was picked
    /// twice, one that cannot play (with its reason), or two that drive the same property of
    /// the same node (naming both channels).
    pub fn play(&mut self, animations: &[usize]) -> Result<(), String> {
        let playing = playing(&self.animations, animations)?;
        self.playing = Some(playing);
        Ok(())
    }

    /// Stops every animation: the nodes stay at rest.
    pub fn stop(&mut self) {
        self.playing = None;
    }

    /// The animations that do not play but move other parts of what plays: another property
    /// of a node that a playing animation moves, or another joint of a skin whose joints a
    /// playing animation moves, without driving anything the playing ones drive. An export
    /// that splits one motion into an animation per joint leaves these out when one is
    /// picked. One that drives what plays too is an alternative (another action of the same
    /// figure), not a part.
    pub fn unplayed_parts(&self) -> Vec<usize> {
        let Some(playing) = &self.playing else { return Vec::new() };
        let skins_of = |tracks: &[Track]| -> Vec<usize> {
            let driven = |place: &usize| tracks.iter().any(|t| t.node == self.rig.nodes[*place].node);
            (self.rig.skins.iter().enumerate())
                .filter(|(_, skin)| skin.joints.iter().map(|(place, _)| place).any(driven))
                .map(|(s, _)| s)
                .collect()
        };
        let played_skins = skins_of(&playing.tracks);
        let is_part = |tracks: &[Track]| {
            let alternative = tracks
                .iter()
                .any(|t| playing.tracks.iter().any(|p| (p.node, p.property) == (t.node, t.property)));
            let same_node = tracks.iter().any(|t| playing.tracks.iter().any(|p| p.node == t.node));
            let same_skin = skins_of(tracks).iter().any(|s| played_skins.contains(s));
            !alternative && (same_node || same_skin)
        };
        (self.animations.iter().enumerate())
            .filter(|(index, _)| !playing.animations.contains(index))
            .filter(|(_, animation)| animation.tracks.as_deref().is_ok_and(is_part))
            .map(|(index, _)| index)
            .collect()
    }
}

/// `picked` of `animations` together, or why they cannot play.
fn playing(animations: &[Animation], picked: &[usize]) -> Result<Playing, String> {
    if picked.is_empty() {
        return Err("no animation is picked".into());
    }
    let several = picked.len() > 1;
    let (mut tracks, mut channel_names) = (Vec::<Track>::new(), Vec::<String>::new());
    let mut labels = Vec::new();
    for (position, &index) in picked.iter().enumerate() {
        let animation = animations.get(index).ok_or_else(|| {
            format!("animations[{index}] does not exist (the file has {})", animations.len())
        })?;
        let label = animation.label(index);
        if picked[..position].contains(&index) {
            return Err(format!("{label} is picked twice"));
        }
        let own = animation.tracks.as_deref().map_err(|error| format!("{label}: {error}"))?;
        for (channel, track) in own.iter().enumerate() {
            let name =
                if several { format!("{label} channels[{channel}]") } else { format!("channels[{channel}]") };
            let same = |other: &Track| (other.node, other.property) == (track.node, track.property);
            if let Some(first) = tracks.iter().position(same) {
                return Err(format!(
                    "{} and {name} both animate the {} of nodes[{}]: played together, which of them sets it \
                     is undefined (glTF forbids it within one animation); pick one of them",
                    channel_names[first],
                    track.property.name(),
                    track.node
                ));
            }
            tracks.push(track.clone());
            channel_names.push(name);
        }
        labels.push((label, animation.name.clone().unwrap_or_else(|| format!("animations[{index}]"))));
    }
    let label = match labels.len() {
        1 => labels[0].0.clone(),
        n => format!("{n} animations played together ({})", joined(labels.iter().map(|l| l.0.as_str()))),
    };
    let short_label = match labels.len() {
        1..=3 => labels.iter().map(|l| l.1.as_str()).collect::<Vec<_>>().join(" + "),
        n => format!("{} and {} more", labels[0].1, n - 1),
    };
    Ok(Playing { animations: picked.to_vec(), tracks, channel_names, label, short_label })
}

/// `a, b and c`.
fn joined<'a>(items: impl Iterator<Item = &'a str>) -> String {
    let items: Vec<&str> = items.collect();
    match items.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} and {last}", rest.join(", ")),
        _ => items.join(""),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::animation::{Interpolation, Property};

    fn track(node: usize, property: Property) -> Track {
        let value = if property == Property::Rotation { [0.0, 0.0, 0.0, 1.0] } else { [1.0; 4] };
        Track {
            node,
            property,
            interpolation: Interpolation::Linear,
            times: vec![0.5, 2.0],
            values: vec![value; 2],
        }
    }

    fn animation(name: &str, tracks: Vec<Track>) -> Animation {
        Animation { name: Some(name.into()), tracks: Ok(tracks) }
    }

    #[test]
    fn several_animations_play_their_tracks_together_on_one_clock() {
        let mut late = track(2, Property::Scale);
        late.times = vec![1.0, 3.5];
        let animations = [
            animation("arm", vec![track(1, Property::Rotation)]),
            animation("leg", vec![track(1, Property::Translation), late]),
        ];
        let playing = playing(&animations, &[1, 0]).unwrap();
        assert_eq!(playing.tracks.len(), 3);
        assert_eq!((playing.start(), playing.duration()), (0.5, 3.5), "the clock spans every track");
        assert_eq!(playing.channel_names[2], r#"animations[0] ("arm") channels[0]"#);
        assert_eq!(playing.short_label, "leg + arm");
        let alone = super::playing(&animations, &[0]).unwrap();
        assert_eq!((alone.channel_names[0].as_str(), alone.short_label.as_str()), ("channels[0]", "arm"));
    }

    #[test]
    fn two_animations_that_drive_one_property_of_one_node_are_refused_naming_both_channels() {
        let animations = [
            animation("walk", vec![track(3, Property::Translation), track(4, Property::Rotation)]),
            animation("run", vec![track(4, Property::Rotation)]),
        ];
        let error = playing(&animations, &[0, 1]).unwrap_err();
        assert!(
            error.starts_with(r#"animations[0] ("walk") channels[1] and animations[1] ("run") channels[0] both animate the rotation of nodes[4]"#),
            "{error}"
        );
        assert!(playing(&animations, &[1, 1]).unwrap_err().contains("picked twice"));
        let broken = [Animation { name: None, tracks: Err("no channels".into()) }];
        assert_eq!(playing(&broken, &[0]).unwrap_err(), "animations[0]: no channels");
        assert!(playing(&broken, &[3]).unwrap_err().contains("does not exist"));
    }
}
