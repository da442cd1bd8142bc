//! The skin data and the procedural rig on the CPU: the `[skin]` table parses and names
//! its bad keys, the rig's weights and matrices do what its docs say, its reach holds every
//! pose, and skins are validated field by field.

use glam::Mat4;
use pelage_scene::{Mesh, SceneFile, Skin, SkinBend};

#[test]
fn the_skin_table_parses_and_names_its_bad_keys() {
    let file = SceneFile::parse("[skin]\nbend = 0.4\ntwist_frequency = 2.0\n").unwrap();
    let skin = file.skin.unwrap();
    assert_eq!((skin.bend, skin.twist_frequency), (0.4, 2.0));
    assert_eq!(skin.origin, SkinBend::default().origin);
    assert!(SceneFile::default().skin.is_none());
    for (text, key) in [
        ("[skin]\nblend = 0.0\n", "skin.blend"),
        ("[skin]\naxis = [0.0, 0.0, 0.0]\n", "skin.axis"),
        ("[skin]\nbend_axis = [0.0, nan, 0.0]\n", "skin.bend_axis"),
        ("[skin]\nbend = -1.0\n", "skin.bend"),
        ("[skin]\ntwist_frequency = 1e9\n", "skin.twist_frequency"),
        ("[skin]\nstiffness = 1.0\n", "stiffness"),
        ("[skin]\n[motion]\n", "skin"),
    ] {
        let message = SceneFile::parse(text).unwrap_err().to_string();
        println!("{text:?}: {message}");
        assert!(message.contains(key), "{text}: {message}");
    }
}

#[test]
fn the_rig_holds_one_side_bends_the_other_and_stays_in_its_reach() {
    let mesh = Mesh::creature();
    let rig = SkinBend::default();
    let skin = rig.skin(&mesh);
    skin.validate(mesh.positions.len()).unwrap();
    let axis = rig.axis.normalize();
    for (p, w) in mesh.positions.iter().zip(&skin.weights) {
        let along = (*p - rig.origin).dot(axis);
        if along <= -rig.blend {
            assert_eq!(w[1], 0.0, "{p}");
        }
        if along >= rig.blend {
            assert_eq!(w[1], 1.0, "{p}");
        }
    }
    let reach = rig.reach(mesh.bounds());
    let mut turned = 0.0f32;
    for i in 0..40 {
        let t = i as f32 * 0.137;
        let [m0, m1] = rig.joint_matrices(t);
        assert_eq!(m0, Mat4::IDENTITY);
        // Joint 1 turns about the origin: the origin stays, distances to it stay.
        assert!(m1.transform_point3(rig.origin).distance(rig.origin) <= 1e-5);
        for (p, w) in mesh.positions.iter().zip(&skin.weights) {
            let q = (m0 * w[0] + m1 * w[1]).transform_point3(*p);
            assert!(
                q.cmpge(reach.0).all() && q.cmple(reach.1).all(),
                "{q} outside {reach:?}"
            );
            if w[1] == 1.0 {
                let d = (q - rig.origin).length() - (*p - rig.origin).length();
                assert!(d.abs() <= 1e-5, "{d}");
                turned = turned.max(q.distance(*p));
            }
        }
    }
    println!("the rig's moving part moves up to {turned:.3} units over 40 poses");
    assert!(turned > 0.3, "{turned}");
}

#[test]
fn skins_are_validated_field_by_field() {
    let good = Skin {
        joints: vec![[0, 1, 2, 0]; 3],
        weights: vec![[0.2, 0.3, 0.5, 0.0]; 3],
        joint_count: 3,
    };
    good.validate(3).unwrap();
    let name = |f: &dyn Fn(&mut Skin), vertices: usize| {
        let mut s = good.clone();
        f(&mut s);
        s.validate(vertices).unwrap_err().name
    };
    assert_eq!(name(&|_| {}, 4), "skin.joints");
    assert_eq!(name(&|s| s.joints[2][3] = 3, 3), "skin.joints[2][3]");
    assert_eq!(name(&|s| s.weights[1][1] = -0.1, 3), "skin.weights[1][1]");
    assert_eq!(
        name(&|s| s.weights[0][0] = f32::INFINITY, 3),
        "skin.weights[0][0]"
    );
    assert_eq!(
        name(&|s| s.weights[2] = [0.2, 0.3, 0.4, 0.0], 3),
        "skin.weights[2]"
    );
    assert_eq!(name(&|s| s.joint_count = 2000, 3), "skin.joint_count");
    // Within the tolerance: accepted, and normalised to sum to 1.
    let mut near = good.clone();
    near.weights[0] = [0.2, 0.3, 0.505, 0.0];
    near.validate(3).unwrap();
    let sum: f32 = near.normalized_weights()[0].iter().sum();
    assert!((sum - 1.0).abs() <= 1e-6, "{sum}");
    // Matrices: count and finiteness.
    assert!(good.check_matrices(&[Mat4::IDENTITY; 3]).is_ok());
    assert_eq!(
        good.check_matrices(&[Mat4::IDENTITY; 2]).unwrap_err().name,
        "skin.joint_matrices"
    );
    let mut bad = [Mat4::IDENTITY; 3];
    bad[2].z_axis.x = f32::NAN;
    assert_eq!(
        good.check_matrices(&bad).unwrap_err().name,
        "skin.joint_matrices[2]"
    );
}
