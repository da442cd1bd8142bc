//! The plugin adds no CPU wait to Bevy's frame: its source (everything that runs in
//! Bevy's frame) never polls the device, maps a buffer, blocks on a future, reads a
//! texture back or submits and waits. Every stage is prepared (queue writes) and
//! recorded into Bevy's own command encoder; Bevy submits.

#[test]
fn the_plugin_never_waits_for_the_gpu() {
    let source = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/src/lib.rs"));
    // The waits wgpu and pelage offer a caller.
    let waits = [
        ".poll(",
        "map_async",
        "block_on",
        "submit_and_wait",
        "read_texture",
        "read_buffer",
        ".finish(&",
        ".submit(",
    ];
    let found: Vec<_> = (source.lines().enumerate())
        .filter(|(_, line)| !line.trim_start().starts_with("//"))
        .flat_map(|(n, line)| {
            (waits.iter())
                .filter(move |w| line.contains(*w))
                .map(move |w| format!("line {}: {w} in `{}`", n + 1, line.trim()))
        })
        .collect();
    assert!(found.is_empty(), "the plugin waits: {found:#?}");
    // The scan sees the plugin's recording (a check that it reads the right file).
    assert!(source.contains("ctx.command_encoder()"));
}
