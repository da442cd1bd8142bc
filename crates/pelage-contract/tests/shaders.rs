//! Every shader under this crate's wgsl/ is listed in `SHADERS` and passes naga validation.

#[test]
fn every_shader_is_listed_and_validates() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/wgsl");
    let count = pelage_contract::SHADERS
        .check_against_dir(dir)
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(count, pelage_contract::SHADERS.files().len());
}
