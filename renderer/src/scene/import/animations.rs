//! The file's animations: their channels read and checked. A broken animation does not cost the
//! file: it stays in the list with the reason it cannot play, which a manifest that picks it is
//! told, naming the animation and the part at fault.

use gltf::json::validation::Checked;

use super::primitives::check_accessor;
use crate::scene::animation::{Animation, Interpolation, Property, Rig, Track};

/// Takes out of the document, before the crate validates it, the animations whose indices or
/// names the crate would refuse the whole file for: an unknown target path or interpolation, a
/// sampler, node or accessor that does not exist. Each keeps its name and loses its channels;
/// returns why, by animation index.
pub(super) fn quarantine(json: &mut gltf::json::Root) -> Vec<(usize, String)> {
    let (accessors, nodes) = (json.accessors.len(), json.nodes.len());
    let mut broken = Vec::new();
    for (index, animation) in json.animations.iter_mut().enumerate() {
        if let Err(error) = structure(animation, accessors, nodes) {
            animation.channels.clear();
            animation.samplers.clear();
            broken.push((index, error));
        }
    }
    broken
}

fn structure(animation: &gltf::json::Animation, accessors: usize, nodes: usize) -> Result<(), String> {
    for (s, sampler) in animation.samplers.iter().enumerate() {
        if sampler.interpolation == Checked::Invalid {
            return Err(format!("samplers[{s}].interpolation is not one of LINEAR, STEP, CUBICSPLINE"));
        }
        for (field, accessor) in [("input", sampler.input), ("output", sampler.output)] {
            if accessor.value() >= accessors {
                return Err(format!(
                    "samplers[{s}].{field}: accessor {} does not exist (the file has {accessors})",
                    accessor.value()
                ));
            }
        }
    }
    for (c, channel) in animation.channels.iter().enumerate() {
        if channel.sampler.value() >= animation.samplers.len() {
            return Err(format!("channels[{c}].sampler: sampler {} does not exist", channel.sampler.value()));
        }
        if channel.target.node.value() >= nodes {
            return Err(format!(
                "channels[{c}].target.node: node {} does not exist",
                channel.target.node.value()
            ));
        }
        if channel.target.path == Checked::Invalid {
            return Err(format!(
                "channels[{c}].target.path is not one of translation, rotation, scale, weights"
            ));
        }
    }
    Ok(())
}

/// Every animation of the file, playable or with the reason it is not.
pub(super) fn import_animations(
    document: &gltf::Document,
    buffers: &[gltf::buffer::Data],
    quarantined: &[(usize, String)],
    rig: &Rig,
) -> Vec<Animation> {
    document
        .animations()
        .map(|animation| {
            let broken = quarantined.iter().find(|(index, _)| *index == animation.index());
            let tracks = match broken {
                Some((_, error)) => Err(error.clone()),
                None => read_tracks(&animation, buffers, rig),
            };
            Animation { name: animation.name().map(str::to_string), tracks }
        })
        .collect()
}

/// An animation's channels as tracks, each checked, and the nodes they move checked too.
fn read_tracks(
    animation: &gltf::Animation,
    buffers: &[gltf::buffer::Data],
    rig: &Rig,
) -> Result<Vec<Track>, String> {
    let tracks = animation
        .channels()
        .map(|channel| {
            read_track(&channel, buffers, rig).map_err(|e| format!("channels[{}]: {e}", channel.index()))
        })
        .collect::<Result<Vec<_>, _>>()?;
    if tracks.is_empty() {
        return Err("no channels".into());
    }
    // glTF forbids it: which of the two would set the property is left undefined.
    for (second, track) in tracks.iter().enumerate() {
        if let Some(first) =
            tracks[..second].iter().position(|t| (t.node, t.property) == (track.node, track.property))
        {
            return Err(format!(
                "channels[{first}] and channels[{second}] both animate the {} of nodes[{}], which glTF forbids",
                track.property.name(),
                track.node
            ));
        }
    }
    if let Some(node) = rig.singular_mover(&tracks) {
        return Err(format!(
            "moves nodes[{node}], whose transform at rest flattens its vertices (a scale of zero), so \
             they cannot be carried from where they were baked"
        ));
    }
    Ok(tracks)
}

fn read_track(
    channel: &gltf::animation::Channel,
    buffers: &[gltf::buffer::Data],
    rig: &Rig,
) -> Result<Track, String> {
    use gltf::animation::util::ReadOutputs;
    let property = match channel.target().property() {
        gltf::animation::Property::Translation => Property::Translation,
        gltf::animation::Property::Rotation => Property::Rotation,
        gltf::animation::Property::Scale => Property::Scale,
        gltf::animation::Property::MorphTargetWeights => {
            return Err("animates morph target weights, which aabench does not read".into());
        }
    };
    let node = channel.target().node().index();
    let Some(rest) = rig.node(node) else {
        return Err(format!("moves nodes[{node}], which the scene does not show"));
    };
    let sampler = channel.sampler();
    check_formats(property, &sampler.input(), &sampler.output())?;
    for (field, accessor) in [("input", sampler.input()), ("output", sampler.output())] {
        check_accessor(&accessor, buffers).map_err(|e| format!("sampler {field}: {e}"))?;
    }
    let reader = channel.reader(|buffer| buffers.get(buffer.index()).map(|d| &d.0[..]));
    let times: Vec<f32> = reader.read_inputs().ok_or("the sampler's input cannot be read")?.collect();
    let widen = |v: [f32; 3]| [v[0], v[1], v[2], 0.0];
    let values: Vec<[f32; 4]> = match reader.read_outputs().ok_or("the sampler's output cannot be read")? {
        ReadOutputs::Translations(values) | ReadOutputs::Scales(values) => values.map(widen).collect(),
        ReadOutputs::Rotations(values) => values.into_f32().collect(),
        ReadOutputs::MorphTargetWeights(_) => unreachable!("refused above"),
    };
    let interpolation = match sampler.interpolation() {
        gltf::animation::Interpolation::Step => Interpolation::Step,
        gltf::animation::Interpolation::Linear => Interpolation::Linear,
        gltf::animation::Interpolation::CubicSpline => Interpolation::CubicSpline,
    };
    let track = Track { node, property, interpolation, times, values };
    track.check()?;
    // Baked triangles keep their winding: a node that turns inside out would show its backs.
    if track.turns_inside_out(rest.scale) {
        return Err(format!(
            "a keyframe's scale mirrors or flattens nodes[{node}] against its rest scale, which aabench \
             does not play (its triangles would turn inside out)"
        ));
    }
    Ok(track)
}

/// The formats glTF allows: float times; float translations and scales; rotations as floats
/// or normalized integers. The crate's readers assume them and panic otherwise.
fn check_formats(property: Property, input: &gltf::Accessor, output: &gltf::Accessor) -> Result<(), String> {
    use gltf::accessor::{DataType, Dimensions};
    if (input.data_type(), input.dimensions()) != (DataType::F32, Dimensions::Scalar) {
        return Err(format!("sampler input: accessors[{}] must hold float scalars (times)", input.index()));
    }
    let format = (output.data_type(), output.dimensions());
    let allowed = match property {
        Property::Rotation => {
            let integer = matches!(format.0, DataType::I8 | DataType::U8 | DataType::I16 | DataType::U16);
            format.1 == Dimensions::Vec4 && (format.0 == DataType::F32 || (integer && output.normalized()))
        }
        _ => format == (DataType::F32, Dimensions::Vec3),
    };
    if !allowed || output.sparse().is_some() || input.sparse().is_some() {
        let (data_type, dimensions) = format;
        return Err(format!(
            "sampler output: accessors[{}] holds {dimensions:?} of {data_type:?}{}, not a format glTF allows for {property:?}",
            output.index(),
            if output.sparse().is_some() || input.sparse().is_some() { " (sparse)" } else { "" }
        ));
    }
    Ok(())
}
