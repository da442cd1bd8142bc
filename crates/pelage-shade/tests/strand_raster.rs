//! The strand rasterizer (`StrandRaster`, `shade/oit/strand_raster.wgsl`) on a real
//! adapter: against the exact composite, its CPU mirror, and the regimes where a
//! compute rasterizer breaks (huge and sub-pixel segments, the near plane, overflow).

mod support;

use pelage_scene::{Camera, Transparency};
use support::*;

#[test]
fn draws_the_creature_close_to_exact() {
    let gpu = gpu();
    for opacity in [0.3, 0.8] {
        let s = scene(&gpu, 3000, opacity, Camera::default());
        let truth = exact(&gpu, &s);
        let (raster, stats) = render(&gpu, &s, Transparency::strand_raster());
        let (k8, _) = render(&gpu, &s, Transparency::k_buffer(8));
        let fr = mean_flip(&truth.image, &raster);
        let fk = mean_flip(&truth.image, &k8);
        println!(
            "opacity {opacity}: mean FLIP strand raster {fr:.4}, k-buffer k=8 {fk:.4}; {stats:?}"
        );
        let differs = (0..truth.depth.len())
            .filter(|&p| raster[4 * p..4 * p + 3] != truth.background[4 * p..4 * p + 3])
            .count();
        println!("  {differs} pixels differ from the background");
        assert!(fr < 0.1);
    }
}
