//! Every WGSL shader parses, validates, and translates to GLSL ES 3.00 (the WebGL2 path).

// A test crate: fixture helpers fail loudly on purpose.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use naga::back::glsl;
use naga::valid::{Capabilities, ValidationFlags, Validator};

#[test]
fn every_shader_validates_and_translates_for_webgl2() {
    assert!(!stance_render::SHADERS.is_empty());
    for (name, source) in stance_render::SHADERS {
        let module = naga::front::wgsl::parse_str(source)
            .unwrap_or_else(|error| panic!("{name}: {}", error.emit_to_string(source)));
        let info = Validator::new(ValidationFlags::all(), Capabilities::empty())
            .validate(&module)
            .unwrap_or_else(|error| panic!("{name}: {error:?}"));
        for entry_point in &module.entry_points {
            let options = glsl::Options {
                version: glsl::Version::Embedded {
                    version: 300,
                    is_webgl: true,
                },
                ..Default::default()
            };
            let pipeline_options = glsl::PipelineOptions {
                shader_stage: entry_point.stage,
                entry_point: entry_point.name.clone(),
                multiview: None,
            };
            let mut output = String::new();
            glsl::Writer::new(
                &mut output,
                &module,
                &info,
                &options,
                &pipeline_options,
                naga::proc::BoundsCheckPolicies::default(),
            )
            .and_then(|mut writer| writer.write())
            .unwrap_or_else(|error| panic!("{name}/{}: {error:?}", entry_point.name));
            assert!(output.contains("void main()"));
        }
    }
}

/// A shader file added to `src/shaders/` but not to `SHADERS` would escape validation: the
/// list and the directory must name the same files.
#[test]
fn the_validated_list_names_every_shader_file() {
    let directory = concat!(env!("CARGO_MANIFEST_DIR"), "/src/shaders");
    let mut on_disk: Vec<String> = std::fs::read_dir(directory)
        .unwrap()
        .map(|entry| entry.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|name| name.ends_with(".wgsl"))
        .collect();
    on_disk.sort();
    let mut listed: Vec<String> = stance_render::SHADERS
        .iter()
        .map(|(name, _)| (*name).to_owned())
        .collect();
    listed.sort();
    assert_eq!(on_disk, listed);
}
