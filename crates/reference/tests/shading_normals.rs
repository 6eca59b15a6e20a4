//! The adjoint shading-normal factor (DESIGN.md "Shading normals in light transport",
//! Veach 1997 §5.3): flat sheets of triangles whose vertex normals ns are all tilted by
//! a known angle from the facet normal ng, under a directional light of irradiance E,
//! over a diffuse floor. Because ns is the same everywhere, the camera-side answer is
//! exact and simple:
//!
//! - **mirror** (reflectance ρ): a camera path sees the light's radiance times ρ along
//!   ωo = mirror(ωi) about ns, and mirroring about a fixed normal preserves solid
//!   angle, so the reflected beam has irradiance ρ·E on a plane ⟂ ωo. It leaves the
//!   mirror's area A through the cross-section A·|ωo·ng|: flux ρ·E·A·|ωo·ng|.
//! - **glass sheet** (one interface, n = 1.5, floor below and parallel): under the
//!   sheet the radiance along ωt is η²·(1 − R)·L (R at the angle to ns, η = 1.5:
//!   radiance scales by η² across an interface, Veach §5.2), and Snell about ns maps
//!   |ωi·ns|·dωi = η²·|ωt·ns|·dωt, so the transmitted beam has irradiance
//!   (1 − R)·E·|ωi·ns|/|ωt·ns| on a plane ⟂ ωt, and the floor (normal ng) gets that
//!   times |ωt·ng|.
//!
//! A light tracer without the factor carries the incident flux E·A·|ωi·ng| times ρ (or
//! 1 − R) instead; the tilts are chosen so the two answers differ by over 20%, far
//! beyond the noise. Each test checks both the floor radiance (rendered image, k·σ
//! with the renderer's own standard error) and the total flux (the power hook, σ from
//! independent seeds).
//!
//! A coarse glass icosphere with analytic vertex normals has no such closed form; the
//! check there is that its caustic power converges to the analytic sphere's as the
//! mesh is refined, with the factor applied at every vertex.

use caustics_reference::{Reference, ReferenceOptions, ReferenceResult};
use caustics_scene::{Scene, Vec3};
use std::collections::HashMap;
use std::f64::consts::PI;

/// An OBJ of an n × n grid of quads (two triangles each) centred at `c`, spanning
/// ±`half[0]` along `u` and ±`half[1]` along `v`, wound counter-clockwise seen from
/// u × v (the facet normal), with every vertex normal equal to `ns`.
fn sheet_obj(c: Vec3, u: Vec3, v: Vec3, half: [f32; 2], n: u32, ns: Vec3) -> String {
    let mut s = String::new();
    for j in 0..=n {
        for i in 0..=n {
            let a = -1.0 + 2.0 * i as f32 / n as f32;
            let b = -1.0 + 2.0 * j as f32 / n as f32;
            let p = c + a * half[0] * u + b * half[1] * v;
            s += &format!("v {} {} {}\nvn {} {} {}\n", p.x, p.y, p.z, ns.x, ns.y, ns.z);
        }
    }
    let id = |i: u32, j: u32| j * (n + 1) + i + 1;
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            s += &format!("f {a}//{a} {b}//{b} {c}//{c}\nf {a}//{a} {c}//{c} {d}//{d}\n");
        }
    }
    s
}

/// The scene `json` with its mesh `sheet.obj` holding `obj`.
/// (The mesh is read while the scene loads, so its folder goes when this returns.)
fn scene_with_sheet(obj: &str, json: &str) -> Scene {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("sheet.obj"), obj).expect("write obj");
    Scene::from_json_str(json, &dir.path().join("scene.json")).expect("valid test scene")
}

/// Mean and standard error of channel 0 over the pixels whose footprint on the floor
/// y = 0 (the four corner rays) lies inside `inside`, and how many there are.
fn floor_block(
    scene: &Scene,
    r: &ReferenceResult,
    inside: impl Fn(Vec3) -> bool,
) -> (f64, f64, usize) {
    let cam = &scene.camera;
    let (mut sum, mut var, mut n) = (0.0, 0.0, 0usize);
    for y in 0..cam.height {
        for x in 0..cam.width {
            let all_in = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
                .into_iter()
                .all(|(dx, dy)| {
                    let (o, d) = cam.ray_through_pixel(x as f32 + dx, y as f32 + dy);
                    let t = -o.y / d.y;
                    t > 0.0 && inside(o + t * d)
                });
            if all_in {
                sum += r.caustic.at(x, y)[0] as f64;
                var += (r.caustic_stderr.at(x, y)[0] as f64).powi(2);
                n += 1;
            }
        }
    }
    (sum / n as f64, var.sqrt() / n as f64, n)
}

/// Total caustic power on the floor (object 1) from `seeds` independent runs of
/// `photons` each: mean and its standard error from the spread of the runs.
fn floor_power(reference: &Reference, photons: u64, seeds: u64) -> (f64, f64) {
    let runs: Vec<f64> = (1..=seeds)
        .map(|seed| {
            let opts = ReferenceOptions {
                photons,
                seed,
                ..Default::default()
            };
            reference
                .caustic_power(&opts, &|object, _| object == 1)
                .expect("traces")[0]
        })
        .collect();
    let k = runs.len() as f64;
    let mean = runs.iter().sum::<f64>() / k;
    let var = runs.iter().map(|p| (p - mean).powi(2)).sum::<f64>() / (k - 1.0);
    (mean, (var / k).sqrt())
}

/// Exact unpolarized Fresnel reflectance from air into `n` at incidence cos_i.
fn fresnel_r(cos_i: f64, n: f64) -> f64 {
    let sin_t = (1.0 - cos_i * cos_i).sqrt() / n;
    let cos_t = (1.0 - sin_t * sin_t).sqrt();
    let rs = (cos_i - n * cos_t) / (cos_i + n * cos_t);
    let rp = (n * cos_i - cos_t) / (n * cos_i + cos_t);
    0.5 * (rs * rs + rp * rp)
}

fn dot(a: Vec3, b: Vec3) -> f64 {
    a.dot(b) as f64
}

/// Asserts that the rendered `got` (± `se`) matches the camera-side `camera` within
/// 4σ and is far (> 10σ) from the uncorrected light tracer's `flux_conserving`, so
/// the check can tell the two apart.
fn assert_camera_side(what: &str, got: f64, se: f64, camera: f64, flux_conserving: f64) {
    eprintln!(
        "{what}: {got:.5} ± {se:.1e}, camera-side {camera:.5}, without the factor {flux_conserving:.5}"
    );
    assert!(
        (got - camera).abs() < 4.0 * se,
        "{what}: {got} vs camera-side {camera}, σ {se}"
    );
    assert!(
        (camera - flux_conserving).abs() > 10.0 * se,
        "{what}: σ {se} too large to tell {camera} from {flux_conserving}"
    );
}

/// A mirror wall x = 0 (facet normal +x, 2 m high, 4 m wide, 4 × 4 quads) with vertex
/// normals tilted 5° up, lit 60° from its normal: |ωo·ng| = cos 50° against
/// |ωi·ng| = cos 60°, a 29% difference in the reflected flux.
#[test]
fn tilted_mirror_matches_camera_side() {
    let tilt = 5f32.to_radians();
    let ns = Vec3::new(tilt.cos(), tilt.sin(), 0.0);
    let ng = Vec3::X;
    let light = Vec3::new(-0.5, -(0.75f32).sqrt(), 0.0);
    let obj = sheet_obj(
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::Y,
        Vec3::Z,
        [1.0, 2.0],
        4,
        ns,
    );
    let json = r#"{"name": "tilted mirror",
        "camera": {"eye": [3, 2, 0], "target": [0.85, 0, 0], "up": [0, 1, 0],
                   "fov_y_deg": 20, "width": 24, "height": 18},
        "lights": [{"type": "directional", "direction": [-0.5, -0.8660254, 0], "irradiance": [1, 1, 1]}],
        "materials": {"chrome": {"type": "mirror", "reflectance": [0.9, 0.9, 0.9]},
                      "floor": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}},
        "objects": [
          {"shape": {"type": "mesh", "path": "sheet.obj"}, "material": "chrome"},
          {"shape": {"type": "quad", "center": [0, 0, 0], "normal": [0, 1, 0], "size": [8, 8]}, "material": "floor"}
        ]}"#;
    let scene = scene_with_sheet(&obj, json);
    let reference = Reference::new(&scene).expect("prepares");

    let wi = -light;
    let wo = 2.0 * wi.dot(ns) * ns - wi;
    let (rho, albedo, area) = (0.9, 0.8, 8.0);
    let camera_flux = rho * area * dot(wo, ng);
    let uncorrected_flux = rho * area * dot(wi, ng);
    // The floor irradiance under the beam: its flux over its footprint A·|ωo·ng|/|ωo·y|.
    let to_radiance = albedo / PI * (-wo.y as f64) / (area * dot(wo, ng));

    // The footprint: x from 0 to 2 m·|ωo.x/ωo.y|, |z| < 2; kept 0.1 m inside.
    let reach = 2.0 * wo.x / -wo.y;
    let r = reference
        .render(
            &ReferenceOptions {
                photons: 1 << 19,
                ..Default::default()
            },
            &|_| {},
        )
        .expect("renders");
    let (mean, se, n) = floor_block(&scene, &r, |p| {
        p.x > 0.1 && p.x < reach - 0.1 && p.z.abs() < 1.9
    });
    assert!(n >= 40, "only {n} pixels inside the reflected beam");
    assert_camera_side(
        "mirror floor radiance",
        mean,
        se,
        camera_flux * to_radiance,
        uncorrected_flux * to_radiance,
    );

    let (power, se) = floor_power(&reference, 1 << 16, 8);
    assert_camera_side("mirror flux (W)", power, se, camera_flux, uncorrected_flux);
}

/// A glass sheet y = 1 (facet normal +y, 4 m × 4 m, 4 × 4 quads) with vertex normals
/// tilted 10° towards +x, lit 60° from its normal from the −x side: the factor
/// |ωi·ns|·|ωt·ng| / (|ωi·ng|·|ωt·ns|) is 0.77 here. The camera sits between sheet
/// and floor (as in analytic.rs's flat interface).
#[test]
fn tilted_glass_sheet_matches_camera_side() {
    let tilt = 10f32.to_radians();
    let ns = Vec3::new(tilt.sin(), tilt.cos(), 0.0);
    let ng = Vec3::Y;
    let light = Vec3::new((0.75f32).sqrt(), -0.5, 0.0);
    let obj = sheet_obj(
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::Z,
        Vec3::X,
        [2.0, 2.0],
        4,
        ns,
    );
    let json = r#"{"name": "tilted glass",
        "camera": {"eye": [0.5, 0.8, 3], "target": [0.5, 0, 0], "up": [0, 1, 0],
                   "fov_y_deg": 30, "width": 24, "height": 18},
        "lights": [{"type": "directional", "direction": [0.8660254, -0.5, 0], "irradiance": [1, 1, 1]}],
        "materials": {"glass": {"type": "dielectric", "ior": 1.5},
                      "floor": {"type": "diffuse", "albedo": [0.7, 0.7, 0.7]}},
        "objects": [
          {"shape": {"type": "mesh", "path": "sheet.obj"}, "material": "glass"},
          {"shape": {"type": "quad", "center": [0, 0, 0], "normal": [0, 1, 0], "size": [8, 8]}, "material": "floor"}
        ]}"#;
    let scene = scene_with_sheet(&obj, json);
    let reference = Reference::new(&scene).expect("prepares");

    // Snell about ns (n = 1.5), in f64.
    let wi = -light;
    let cos_i = dot(wi, ns);
    let eta = 1.0 / 1.5;
    let cos_t = (1.0 - eta * eta * (1.0 - cos_i * cos_i)).sqrt();
    let [wix, wiy, wiz] = [wi.x, wi.y, wi.z].map(f64::from);
    let [nx, ny, nz] = [ns.x, ns.y, ns.z].map(f64::from);
    let c = eta * cos_i - cos_t;
    let wt = [
        -eta * wix + c * nx,
        -eta * wiy + c * ny,
        -eta * wiz + c * nz,
    ];
    let wt_ns = wt[0] * nx + wt[1] * ny + wt[2] * nz;
    let wt_ng = wt[1];
    let t = 1.0 - fresnel_r(cos_i, 1.5);
    let (albedo, area) = (0.7, 16.0);
    let camera_flux = t * area * cos_i * wt_ng.abs() / wt_ns.abs();
    let uncorrected_flux = t * area * dot(wi, ng);
    // The floor is parallel to the sheet: the beam keeps its area A.
    let to_radiance = albedo / PI / area;

    // The footprint: the sheet shifted by |ωt.x/ωt.y| (1 m below it); 0.15 m inside.
    let shift = (wt[0] / -wt[1]) as f32;
    let r = reference
        .render(
            &ReferenceOptions {
                photons: 1 << 20,
                ..Default::default()
            },
            &|_| {},
        )
        .expect("renders");
    let (mean, se, n) = floor_block(&scene, &r, |p| {
        (p.x - shift).abs() < 1.85 && p.z.abs() < 1.85
    });
    assert!(n >= 40, "only {n} pixels inside the transmitted beam");
    assert_camera_side(
        "glass floor radiance",
        mean,
        se,
        camera_flux * to_radiance,
        uncorrected_flux * to_radiance,
    );

    let (power, se) = floor_power(&reference, 1 << 16, 8);
    assert_camera_side("glass flux (W)", power, se, camera_flux, uncorrected_flux);
}

/// An icosphere of radius 1 centred at `c` (the icosahedron with each face split in 4,
/// `subdivisions` times: 20·4^k triangles) as OBJ text, with the analytic (radial)
/// vertex normals, wound counter-clockwise seen from outside.
fn icosphere_obj(c: Vec3, subdivisions: u32) -> (String, usize) {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut v: Vec<Vec3> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .map(|p| Vec3::from_array(p).normalize())
    .to_vec();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        // Edge midpoints, shared by the two faces of an edge, pushed onto the sphere.
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, v: &mut Vec<Vec3>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                v.push((v[a as usize] + v[b as usize]).normalize());
                v.len() as u32 - 1
            })
        };
        faces = faces
            .into_iter()
            .flat_map(|[a, b, c]| {
                let (ab, bc, ca) = (
                    midpoint(a, b, &mut v),
                    midpoint(b, c, &mut v),
                    midpoint(c, a, &mut v),
                );
                [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
            })
            .collect();
    }
    let mut s = String::new();
    for n in &v {
        let p = c + *n;
        s += &format!("v {} {} {}\nvn {} {} {}\n", p.x, p.y, p.z, n.x, n.y, n.z);
    }
    for [a, b, c] in &faces {
        s += &format!("f {0}//{0} {1}//{1} {2}//{2}\n", a + 1, b + 1, c + 1);
    }
    (s, faces.len())
}

/// Power (W) reaching the floor under a vertical beam of irradiance 1 through the
/// analytic sphere of radius 1 and index n, every order of internal reflection
/// included: the Fresnel integral of energy.rs (see there), midpoint rule over the
/// impact parameter.
fn sphere_floor_power(n: f64) -> f64 {
    let steps = 200_000;
    let mut total = 0.0;
    for i in 0..steps {
        let b = (i as f64 + 0.5) / steps as f64;
        let (ti, tt) = (b.asin(), (b / n).asin());
        let r = fresnel_r(ti.cos(), n);
        let mut frac = if (PI - 2.0 * ti).cos() > 0.0 { r } else { 0.0 };
        let mut carried = (1.0 - r) * (1.0 - r);
        for k in 1..64 {
            let dev = 2.0 * (ti - tt) + (k as f64 - 1.0) * (PI - 2.0 * tt);
            if dev.cos() > 0.0 {
                frac += carried;
            }
            carried *= r;
        }
        total += frac * 2.0 * PI * b / steps as f64;
    }
    total
}

/// Glass icospheres (n = 1.5) of 80, 320 and 1,280 triangles with smooth analytic
/// normals under a vertical beam: the shortfall d of their caustic power against the
/// analytic sphere's must shrink by more than 1.5× per subdivision (3σ, σ from
/// independent seeds). Refining halves the facet size h; the facets' cross-section
/// deficit falls as h² and the normals' deviation from the facets as h, so with a
/// factor that tends to 1 as ns → ng, d should fall at least linearly in h (2× per
/// step; 1.5× leaves room for the rate not yet being asymptotic). This does not single
/// out the factor (the flux-conserving tracer converges too); it checks that the
/// factor, unbounded where a photon grazes a facet, keeps a coarse mesh's energy
/// converging to the sphere's.
#[test]
fn coarse_glass_icosphere_converges_to_the_analytic_sphere() {
    let expected = sphere_floor_power(1.5);
    let shortfalls: Vec<(usize, f64, f64)> = (1..=3)
        .map(|k| {
            let (obj, triangles) = icosphere_obj(Vec3::new(0.0, 2.0, 0.0), k);
            let json = r#"{"name": "icosphere",
                "camera": {"eye": [3, 10, 0], "target": [3, 0, 0], "up": [0, 0, 1],
                           "fov_y_deg": 11.4, "width": 8, "height": 8},
                "lights": [{"type": "directional", "direction": [0, -1, 0], "irradiance": [1, 1, 1]}],
                "materials": {"glass": {"type": "dielectric", "ior": 1.5},
                              "floor": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
                "objects": [
                  {"shape": {"type": "mesh", "path": "sheet.obj"}, "material": "glass"},
                  {"shape": {"type": "quad", "center": [0, 0, 0], "normal": [0, 1, 0], "size": [2000, 2000]}, "material": "floor"}
                ]}"#;
            let scene = scene_with_sheet(&obj, json);
            let reference = Reference::new(&scene).expect("prepares");
            let (power, se) = floor_power(&reference, 1 << 17, 8);
            let d = 1.0 - power / expected;
            eprintln!(
                "icosphere of {triangles} triangles: {power:.5} ± {se:.1e} W vs sphere {expected:.5} W, shortfall {d:.4}"
            );
            (triangles, d, se / expected)
        })
        .collect();
    for pair in shortfalls.windows(2) {
        let [(n0, d0, s0), (n1, d1, s1)] = [pair[0], pair[1]];
        let sigma = (s0 * s0 + 1.5f64.powi(2) * s1 * s1).sqrt();
        assert!(
            d0 - 1.5 * d1 > 3.0 * sigma,
            "{n0} -> {n1} triangles: shortfall {d0} -> {d1} (σ {s0}, {s1})"
        );
    }
}
