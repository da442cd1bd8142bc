//! The shaders of every crate together: each compiles on the device, and every shading
//! pass composes with every implementation of the shadow contract, found through the
//! shadow crate's sources the way a `ShaderBinding` brings them.

use pelage::gpu::{Gpu, Redirect, SHADERS as GPU_SHADERS, ShaderSources};
use pelage::{contract, shade, shadow, strands};

/// Every crate's sources.
const ALL: [&ShaderSources; 5] = [
    &GPU_SHADERS,
    &contract::SHADERS,
    &strands::SHADERS,
    &shadow::SHADERS,
    &shade::SHADERS,
];

#[test]
fn every_shader_compiles_on_the_device() {
    let gpu = Gpu::headless().unwrap_or_else(|e| panic!("these tests need a GPU adapter: {e}"));
    let mut count = 0;
    for sources in ALL {
        let library = sources.library();
        for name in sources.names() {
            library
                .module(&gpu, name)
                .unwrap_or_else(|e| panic!("{}: {e}", sources.crate_name()));
            count += 1;
        }
    }
    assert!(count > 50, "only {count} shaders");
}

#[test]
fn shading_passes_compose_with_every_shadow_implementation() {
    // Every file that implements the shadow contract (`light_visibility`), by naming
    // convention: the contract's own trivial one and each method's lookup.
    let lookups: Vec<&'static str> = (shadow::SHADERS.names())
        .filter(|n| n.ends_with("_lookup.wgsl"))
        .collect();
    assert!(lookups.contains(&"shadow/voxel_lookup.wgsl"), "{lookups:?}");
    let mut redirects = vec![Redirect::new(shadow::CONTRACT, shadow::CONTRACT)];
    redirects.extend(
        (lookups.iter()).map(|&to| Redirect::to_sources(shadow::CONTRACT, to, &shadow::SHADERS)),
    );
    let library = shade::SHADERS.library();
    for pass in [
        "shade/mesh.wgsl",
        "shade/ribbons.wgsl",
        "shade/oit/wboit.wgsl",
        "shade/oit/k_buffer.wgsl",
        "shade/oit/a_buffer.wgsl",
        "shade/oit/dbk.wgsl",
        "shade/oit/random_subsets.wgsl",
        "shade/oit/strand_raster.wgsl",
    ] {
        // Only the passes that shade with the key light's shadow (the mesh) import the
        // contract; the hair reads stage 2's per-vertex visibility buffer instead.
        let imports_contract = library
            .compose_redirected(pass, &[])
            .unwrap_or_else(|e| panic!("{pass}: {e}"))
            .contains(&format!("// --- begin {}", shadow::CONTRACT));
        for redirect in &redirects {
            let text = library
                .compose_redirected(pass, &[*redirect])
                .unwrap_or_else(|e| panic!("{pass} with {}: {e}", redirect.to));
            assert_eq!(
                text.contains(&format!("// --- begin {}", redirect.to)),
                imports_contract,
                "{pass} with {}",
                redirect.to
            );
            library
                .validate_redirected(pass, &[*redirect])
                .unwrap_or_else(|e| panic!("{pass} with {}: {e}", redirect.to));
        }
    }
    // The shading stage alone cannot see the shadow methods' files.
    assert!(library.source("shadow/voxel_lookup.wgsl").is_err());
}

#[test]
fn the_viewers_shaders_are_listed_and_validate() {
    static VIEWER: ShaderSources =
        pelage::gpu::wgsl_sources!(in "examples/wgsl"; "present/blit.wgsl");
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/wgsl");
    assert_eq!(
        VIEWER
            .check_against_dir(dir)
            .unwrap_or_else(|e| panic!("{e}")),
        1
    );
}
