//! The scene options `render` and `animate` share: a scene file and what the command
//! line overrides in it.

use std::path::PathBuf;
use std::str::FromStr;

use clap::ValueEnum;
use pelage::scene::Scene;
use pelage::scene::{
    Light, MultipleScattering, Named, ParamError, ShadingModel, ShadowParams, Transparency,
};

use crate::error::CliError;

/// An image size, `WxH` on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Size {
    /// Pixels across.
    pub width: u32,
    /// Pixels down.
    pub height: u32,
}

impl FromStr for Size {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        let (w, h) = text
            .split_once(['x', 'X'])
            .ok_or_else(|| format!("expected WxH in pixels, e.g. 480x360, not `{text}`"))?;
        let side = |v: &str| match v.trim().parse::<u32>() {
            Ok(n) if n > 0 => Ok(n),
            _ => Err(format!(
                "`{v}` in `{text}`: width and height are whole numbers of pixels from 1 to {}",
                u32::MAX
            )),
        };
        Ok(Self {
            width: side(w)?,
            height: side(h)?,
        })
    }
}

impl std::fmt::Display for Size {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}x{}", self.width, self.height)
    }
}

/// A parser of one method table ([`Named::NAMES`]): the table's names and aliases are the
/// values the command line accepts, their summaries its help. Scene files read the same
/// table, so `--shadow deep_opacity` and `method = "deep_opacity"` are one method.
fn method<T>() -> impl clap::builder::TypedValueParser<Value = T>
where
    T: Named + Clone + Send + Sync + 'static,
{
    use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
    PossibleValuesParser::new(T::NAMES.iter().map(|m| {
        PossibleValue::new(m.name)
            .aliases(m.aliases.iter().copied())
            .help(m.summary)
    }))
    .try_map(|name: String| {
        T::named(&name).ok_or_else(|| {
            format!(
                "unknown method `{name}`; the known ones: {}",
                T::name_list()
            )
        })
    })
}

/// The scene's model switched to `model`: a scene that already uses this model keeps its
/// parameters (`marschner` and `marschner_lut` share Marschner's, and only switch the
/// lookup tables); another model starts from `model`'s defaults.
fn model_applied_to(model: &ShadingModel, current: &ShadingModel) -> ShadingModel {
    match (model, current) {
        (ShadingModel::Marschner { lut, .. }, ShadingModel::Marschner { params, .. }) => {
            ShadingModel::Marschner {
                params: params.clone(),
                lut: *lut,
            }
        }
        _ if model.row() == current.row() => current.clone(),
        _ => model.clone(),
    }
}

/// Melanin concentrations on the command line: `EU` or `EU,PHEO`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Melanin {
    /// Eumelanin concentration.
    pub eumelanin: f32,
    /// Pheomelanin concentration, when given.
    pub pheomelanin: Option<f32>,
}

impl FromStr for Melanin {
    type Err = String;

    /// Parses the numbers only; their range is checked with the model's parameters
    /// (and the error then names `--melanin`, [`SceneOpts::blame`]).
    fn from_str(text: &str) -> Result<Self, String> {
        let number = |v: &str, what: &str| {
            v.trim().parse::<f32>().map_err(|e| {
                format!(
                    "{what} `{v}` in `{text}`: {e} (expected EU or EU,PHEO, e.g. 0.3 or 1.3,0.2)"
                )
            })
        };
        match text.split_once(',') {
            Some((eu, pheo)) => Ok(Self {
                eumelanin: number(eu, "eumelanin")?,
                pheomelanin: Some(number(pheo, "pheomelanin")?),
            }),
            None => Ok(Self {
                eumelanin: number(text, "eumelanin")?,
                pheomelanin: None,
            }),
        }
    }
}

/// A switch on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum OnOff {
    /// Enabled.
    On,
    /// Disabled.
    Off,
}

/// Light set-ups by command-line name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
#[value(rename_all = "snake_case")]
pub enum LightsArg {
    /// The key light only (the scene's first light).
    Key,
    /// A white key light and a warm point light behind the hair, each with its own shadow.
    KeyBack,
}

/// A scene file and the command-line options that override it.
#[derive(Clone, Debug, clap::Args)]
pub struct SceneOpts {
    /// Scene file (TOML; scenes/default.toml lists every key with its default). The
    /// options below override it. Default: the built-in furred creature.
    #[arg(long, value_name = "FILE")]
    pub scene: Option<PathBuf>,
    /// Image size in pixels, width x height.
    #[arg(
        long,
        value_name = "WxH",
        default_value = "480x360",
        allow_hyphen_values = true
    )]
    pub size: Size,
    /// Number of strands (the scene's own count by default: 20000 for the built-in scene;
    /// with guides, the render strands interpolated from them).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub strands: Option<u32>,
    /// Shadow method (the scene's by default; the built-in scene's: voxel).
    #[arg(long, value_name = "METHOD", value_parser = method::<ShadowParams>())]
    pub shadow: Option<ShadowParams>,
    /// Shadow resolution: voxels per axis for voxel shadows (default 128), texels per
    /// side for deep_opacity, shadow_map and adsm (default 1024). Applies to --shadow or the scene's method.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub shadow_res: Option<u32>,
    /// Transparency (the scene's by default; the built-in scene's: strand_raster).
    #[arg(long, value_name = "METHOD", value_parser = method::<Transparency>())]
    pub oit: Option<Transparency>,
    /// Hair shading model (the scene's by default; the built-in scene's: chiang). When the scene already
    /// uses this model its parameters are kept (marschner and marschner_lut share them);
    /// another model starts from its defaults.
    #[arg(long, value_name = "MODEL", value_parser = method::<ShadingModel>())]
    pub model: Option<ShadingModel>,
    /// Melanin of the chiang model (--model chiang, or a scene that uses it), as
    /// concentrations, dimensionless, each in [0, 50]: eumelanin EU and optionally
    /// pheomelanin PHEO. The absorption per unit fibre radius is
    /// EU·(0.419, 0.697, 1.37) + PHEO·(0.187, 0.4, 1.05): 0.3 is blond, 1.3 brown, 8 black;
    /// pheomelanin adds red. PHEO left out keeps the scene's (none: 0); a sigma_a of the
    /// scene is replaced. Default: the scene's absorption (none given: from the hair
    /// colour). Refused when the model is not chiang.
    #[arg(long, value_name = "EU[,PHEO]", allow_hyphen_values = true)]
    pub melanin: Option<Melanin>,
    /// Dual scattering of the chiang model: light scattered between fibres, estimated
    /// from the shadows (on), or single scattering only (off); the older spelling of
    /// `--multiple-scattering dual|none`. Default: the scene's (volume unless it says
    /// otherwise). Refused when the model is not chiang.
    #[arg(long, value_name = "on|off", conflicts_with = "multiple_scattering")]
    pub dual_scattering: Option<OnOff>,
    /// Multiple scattering of the chiang model: none, dual, volume (a radiance grid over
    /// the hair) or dual_volume (dual scattering for the lights, the grid for the sky and
    /// the body's bounce). Default: the scene's (volume unless it says otherwise). Refused
    /// when the model is not chiang.
    #[arg(long, value_name = "METHOD", value_parser = method::<MultipleScattering>())]
    pub multiple_scattering: Option<MultipleScattering>,
    /// Lights (the scene's by default: one key light).
    #[arg(long, value_name = "SET")]
    pub lights: Option<LightsArg>,
    /// Level of detail: grow and draw only as many strands and segments as the hair's
    /// size on screen needs (stochastic simplification with the scene's [hair.lod]
    /// parameters, seed 002), and size the shadow grid or maps down to it.
    #[arg(long)]
    pub lod: bool,
}

impl SceneOpts {
    /// The scene file (or the built-in scene) with the command line's overrides applied.
    /// An out-of-range value of an option is an error naming the option
    /// ([`SceneOpts::blame`]).
    pub fn scene(&self) -> Result<Scene, CliError> {
        self.scene_unblamed().map_err(|e| self.blame(e))
    }

    fn scene_unblamed(&self) -> Result<Scene, CliError> {
        let mut scene = match &self.scene {
            Some(path) => Scene::from_file(path)?,
            None => Scene::default(),
        };
        if let Some(shadow) = &self.shadow {
            scene.shadow = shadow.clone();
        }
        if let Some(n) = self.shadow_res {
            match &mut scene.shadow {
                ShadowParams::Voxel(v) => {
                    v.resolution = [n; 3];
                    v.voxel_size = None; // a voxel size would override the resolution
                }
                ShadowParams::DeepOpacity(d) => d.map.size = n,
                ShadowParams::ShadowMap(m) => m.map.size = n,
                ShadowParams::Adsm(a) => a.map.size = n,
                ShadowParams::None => {
                    return Err(CliError::Usage(
                        "--shadow-res: the scene has no shadow method; give --shadow too".into(),
                    ));
                }
            }
        }
        if let Some(oit) = &self.oit {
            scene.shade.transparency = oit.clone();
        }
        if let Some(model) = &self.model {
            scene.shade.model = model_applied_to(model, &scene.shade.model);
        }
        self.apply_chiang_options(&mut scene.shade.model)?;
        match self.lights {
            Some(LightsArg::Key) => {
                scene.lights.truncate(1);
                if scene.lights.is_empty() {
                    scene.lights.push(Light::default());
                }
            }
            Some(LightsArg::KeyBack) => scene.lights = Light::key_and_back(&scene.camera),
            None => {}
        }
        if let (Some(n), Some(guides)) = (self.strands, scene.guides.as_mut()) {
            // Guides interpolated into render strands: --strands counts those.
            guides.strands = n;
        } else if let Some(n) = self.strands {
            if scene.groom.is_some() {
                return Err(CliError::Usage(
                    "--strands: the scene draws a groom file, whose strands are its own; \
                     leave --strands out, or remove the scene's [groom] table to grow fur"
                        .into(),
                ));
            }
            scene.hair.roots.count = n;
        }
        if self.lod {
            scene.hair.lod.enabled = true;
            scene = pelage::strands::sized_for_view(
                &scene,
                &scene.camera,
                self.size.width,
                self.size.height,
            );
        }
        Ok(scene)
    }
}

/// Which scene key each command-line option sets, as errors name the key (a
/// [`ParamError`]'s `name`): the one table that turns an error about a value the
/// command line gave into an error naming the option ([`SceneOpts::blame`]).
pub const OPTION_KEYS: &[(&str, &str)] = &[
    ("--size", "image size"),
    ("--strands", "roots.count"),
    ("--strands", "guides.strands"),
    ("--shadow-res", "shadow.resolution"),
    ("--shadow-res", "shadow.deep_opacity.size"),
    ("--shadow-res", "shadow.shadow_map.size"),
    ("--shadow-res", "shadow.adsm.size"),
    ("--melanin", "shading.chiang.eumelanin"),
    ("--melanin", "shading.chiang.pheomelanin"),
];

/// The parameter error inside `e`, if it is one.
fn param_error(e: &CliError) -> Option<&ParamError> {
    use pelage::{shade::ShadeError, shadow::ShadowError, strands::StrandsError};
    match e {
        CliError::Render(
            pelage::Error::Param(p)
            | pelage::Error::Contract(pelage::contract::ContractError::Param(p))
            | pelage::Error::Strands(StrandsError::Param(p))
            | pelage::Error::Shadow(ShadowError::Param(p))
            | pelage::Error::Shade(ShadeError::Param(p)),
        ) => Some(p),
        _ => None,
    }
}

impl SceneOpts {
    /// Whether `option` was given and set `key` (an entry of [`OPTION_KEYS`]): `--size`
    /// always is (its default is the option's), `--melanin` sets pheomelanin only
    /// when it names it.
    fn sets(&self, option: &str, key: &str) -> bool {
        match option {
            "--size" => true,
            "--strands" => self.strands.is_some(),
            "--shadow-res" => self.shadow_res.is_some(),
            "--melanin" => self
                .melanin
                .is_some_and(|m| key != "shading.chiang.pheomelanin" || m.pheomelanin.is_some()),
            _ => false,
        }
    }

    /// `e`, naming the option instead of the scene key when it is about a value an option
    /// gave (see [`OPTION_KEYS`]): a usage error (exit code 2) that names the option, the
    /// value, its range and the key it sets. Other errors are returned as they are.
    pub fn blame(&self, e: CliError) -> CliError {
        let Some(param) = param_error(&e) else {
            return e;
        };
        match OPTION_KEYS
            .iter()
            .find(|(option, key)| *key == param.name && self.sets(option, key))
        {
            Some((option, key)) => CliError::Usage(format!(
                "{option} = {}: {} ({option} sets `{key}`)",
                param.value, param.reason
            )),
            None => e,
        }
    }
}

impl SceneOpts {
    /// Applies --melanin and --dual-scattering to `model`, which must be Chiang's when
    /// either is given, then checks the model's parameters (a bad value is an error that
    /// names the parameter, `shading.chiang.eumelanin` say, which [`SceneOpts::scene`]
    /// turns into one naming `--melanin`, with exit code 2).
    fn apply_chiang_options(&self, model: &mut ShadingModel) -> Result<(), CliError> {
        let given: Vec<&str> = [
            self.melanin.map(|_| "--melanin"),
            self.dual_scattering.map(|_| "--dual-scattering"),
            self.multiple_scattering.map(|_| "--multiple-scattering"),
        ]
        .into_iter()
        .flatten()
        .collect();
        if given.is_empty() {
            return Ok(());
        }
        let ShadingModel::Chiang(params) = model else {
            return Err(CliError::Usage(format!(
                "{}: only the chiang model has this, and the model is {}; give --model chiang too",
                given.join(", "),
                model.name()
            )));
        };
        if let Some(melanin) = self.melanin {
            params.eumelanin = Some(melanin.eumelanin);
            if let Some(pheomelanin) = melanin.pheomelanin {
                params.pheomelanin = Some(pheomelanin);
            }
            // Melanin and a given sigma_a exclude each other: the option replaces it.
            params.sigma_a = None;
        }
        if let Some(dual) = self.dual_scattering {
            params.multiple_scattering = if dual == OnOff::On {
                MultipleScattering::Dual
            } else {
                MultipleScattering::None
            };
        }
        if let Some(method) = self.multiple_scattering {
            params.multiple_scattering = method;
        }
        model
            .validate()
            .map_err(|e| CliError::Render(pelage::Error::Param(e)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The help names the built-in scene's methods as they are (it said `opaque` and
    /// `kajiya_kay` for a release after the defaults changed).
    #[test]
    fn the_help_names_the_built_in_scenes_methods() {
        use clap::{Args, Command};
        let help = SceneOpts::augment_args(Command::new("t"))
            .render_long_help()
            .to_string();
        let scene = pelage::scene::Scene::default();
        let voxel = matches!(scene.shadow, ShadowParams::Voxel(_));
        assert!(voxel, "the help says voxel: update it");
        for name in [
            "voxel",
            scene.shade.transparency.name(),
            scene.shade.model.name(),
        ] {
            let said = format!("the built-in scene's: {name})");
            assert!(help.contains(&said), "`{said}` not in the help:\n{help}");
        }
    }

    #[test]
    fn sizes() {
        assert_eq!(
            "96x72".parse::<Size>(),
            Ok(Size {
                width: 96,
                height: 72
            })
        );
        assert!("96".parse::<Size>().is_err());
        assert!("0x72".parse::<Size>().is_err());
        assert!("ax72".parse::<Size>().is_err());
    }

    #[test]
    fn melanin_parses_one_or_two_numbers() {
        assert_eq!(
            "0.3".parse::<Melanin>(),
            Ok(Melanin {
                eumelanin: 0.3,
                pheomelanin: None
            })
        );
        assert_eq!(
            " 1.3 , 0.2".parse::<Melanin>(),
            Ok(Melanin {
                eumelanin: 1.3,
                pheomelanin: Some(0.2)
            })
        );
        // Out-of-range numbers parse: the model's check names them.
        assert!("-1".parse::<Melanin>().is_ok());
        assert!("nan".parse::<Melanin>().unwrap().eumelanin.is_nan());
        assert!("".parse::<Melanin>().is_err());
        assert!("brown".parse::<Melanin>().is_err());
        assert!("1,".parse::<Melanin>().is_err());
        assert!("1,2,3".parse::<Melanin>().is_err());
    }

    /// The scene options `args` parse to.
    fn opts(args: &[&str]) -> SceneOpts {
        #[derive(clap::Parser)]
        struct Cli {
            #[command(flatten)]
            scene: SceneOpts,
        }
        use clap::Parser;
        Cli::try_parse_from(std::iter::once("pelage").chain(args.iter().copied()))
            .unwrap_or_else(|e| panic!("{args:?}: {e}"))
            .scene
    }

    /// A scene file with this `[shade.model]` table, in a folder of its own.
    struct SceneWith(std::path::PathBuf);

    impl SceneWith {
        fn new(name: &str, model: &str) -> Self {
            let dir = std::env::temp_dir()
                .join(format!("pelage-scene-opts-{}-{name}", std::process::id()));
            std::fs::create_dir_all(&dir).unwrap();
            let path = dir.join("scene.toml");
            std::fs::write(&path, format!("[shade.model]\n{model}\n")).unwrap();
            Self(path)
        }

        fn model(&self, args: &[&str]) -> Result<ShadingModel, CliError> {
            let path = self.0.to_string_lossy().into_owned();
            let mut all = vec!["--scene", path.as_str()];
            all.extend_from_slice(args);
            opts(&all).scene().map(|s| s.shade.model)
        }
    }

    impl Drop for SceneWith {
        fn drop(&mut self) {
            if let Some(dir) = self.0.parent() {
                let _ = std::fs::remove_dir_all(dir);
            }
        }
    }

    #[test]
    fn model_keeps_the_scene_parameters_of_that_model() {
        use pelage::scene::{ChiangParams, KajiyaKayParams, MarschnerParams, SadeghiParams};
        let marschner = |lut| ShadingModel::Marschner {
            params: MarschnerParams {
                eta: 1.6,
                ..Default::default()
            },
            lut,
        };
        let kk = ShadingModel::KajiyaKay(KajiyaKayParams {
            shininess: 20.0,
            ..Default::default()
        });
        let sadeghi = ShadingModel::Sadeghi(SadeghiParams {
            diffuse: 0.1,
            ..Default::default()
        });
        let chiang = ShadingModel::Chiang(ChiangParams {
            beta_m: 0.5,
            eumelanin: Some(2.0),
            ..Default::default()
        });
        let cases: [(&str, &str, ShadingModel, ShadingModel); 5] = [
            (
                "kajiya_kay",
                "model = \"kajiya_kay\"\nshininess = 20.0",
                kk.clone(),
                kk,
            ),
            (
                "marschner",
                "model = \"marschner\"\neta = 1.6",
                marschner(false),
                marschner(false),
            ),
            (
                "marschner_lut",
                "model = \"marschner\"\nlut = true\neta = 1.6",
                marschner(true),
                marschner(true),
            ),
            (
                "sadeghi",
                "model = \"sadeghi\"\ndiffuse = 0.1",
                sadeghi.clone(),
                sadeghi,
            ),
            (
                "chiang",
                "model = \"chiang\"\nbeta_m = 0.5\neumelanin = 2.0",
                chiang.clone(),
                chiang,
            ),
        ];
        for (name, table, scene_model, expected) in cases {
            let scene = SceneWith::new(name, table);
            assert_eq!(scene.model(&[]).unwrap(), scene_model, "{name}");
            assert_eq!(scene.model(&["--model", name]).unwrap(), expected, "{name}");
        }
        // marschner and marschner_lut switch the tables and keep the parameters.
        let scene = SceneWith::new("switch", "model = \"marschner\"\neta = 1.6");
        assert_eq!(
            scene.model(&["--model", "marschner_lut"]).unwrap(),
            marschner(true)
        );
        let scene = SceneWith::new(
            "switch_back",
            "model = \"marschner\"\nlut = true\neta = 1.6",
        );
        assert_eq!(
            scene.model(&["--model", "marschner"]).unwrap(),
            marschner(false)
        );
        // Another model starts from its defaults.
        assert_eq!(
            scene.model(&["--model", "chiang"]).unwrap(),
            ShadingModel::Chiang(ChiangParams::default())
        );
        assert_eq!(
            scene.model(&["--model", "kajiya_kay"]).unwrap(),
            ShadingModel::KajiyaKay(KajiyaKayParams::default())
        );
    }

    #[test]
    fn chiang_options_set_melanin_and_dual_scattering_and_nothing_else() {
        use pelage::scene::ChiangParams;
        let scene = SceneWith::new(
            "chiang_opts",
            "model = \"chiang\"\nbeta_m = 0.5\npheomelanin = 0.4",
        );
        let ShadingModel::Chiang(p) = scene.model(&["--melanin", "1.3"]).unwrap() else {
            panic!("not chiang");
        };
        assert_eq!(
            p,
            ChiangParams {
                beta_m: 0.5,
                eumelanin: Some(1.3),
                pheomelanin: Some(0.4),
                ..Default::default()
            }
        );
        let ShadingModel::Chiang(p) = scene
            .model(&["--melanin", "8,0", "--dual-scattering", "off"])
            .unwrap()
        else {
            panic!("not chiang");
        };
        assert_eq!(
            (p.eumelanin, p.pheomelanin, p.multiple_scattering, p.beta_m),
            (Some(8.0), Some(0.0), MultipleScattering::None, 0.5)
        );
        let ShadingModel::Chiang(p) = scene.model(&["--multiple-scattering", "volume"]).unwrap()
        else {
            panic!("not chiang");
        };
        assert_eq!(p.multiple_scattering, MultipleScattering::Volume);
        // A scene's sigma_a gives way to the melanin of the command line.
        let sigma = SceneWith::new(
            "chiang_sigma",
            "model = \"chiang\"\nsigma_a = [0.1, 0.2, 0.3]",
        );
        let ShadingModel::Chiang(p) = sigma.model(&["--melanin", "0.3"]).unwrap() else {
            panic!("not chiang");
        };
        assert_eq!((p.sigma_a, p.eumelanin), (None, Some(0.3)));
        // The built-in scene with --model chiang.
        let model = opts(&["--model", "chiang", "--melanin", "0.3"])
            .scene()
            .unwrap()
            .shade
            .model;
        assert_eq!(
            model,
            ShadingModel::Chiang(ChiangParams {
                eumelanin: Some(0.3),
                ..Default::default()
            })
        );
    }

    #[test]
    fn chiang_options_refuse_another_model_and_bad_values() {
        for args in [
            &["--model", "kajiya_kay", "--melanin", "0.3"][..],
            &["--model", "kajiya_kay", "--dual-scattering", "off"],
            &["--model", "marschner", "--melanin", "0.3"],
            &["--model", "sadeghi", "--dual-scattering", "on"],
            &["--model", "sadeghi", "--multiple-scattering", "volume"],
        ] {
            let e = opts(args).scene().unwrap_err();
            let m = e.to_string();
            assert!(matches!(e, CliError::Usage(_)), "{args:?}: {m}");
            assert_eq!(e.exit_code(), 2);
            let option = args[args.len() - 2];
            assert!(m.contains(option) && m.contains("chiang"), "{args:?}: {m}");
        }
        for (value, key) in [
            ("-0.5", "shading.chiang.eumelanin"),
            ("nan", "shading.chiang.eumelanin"),
            ("inf", "shading.chiang.eumelanin"),
            ("51", "shading.chiang.eumelanin"),
            ("0.3,-1", "shading.chiang.pheomelanin"),
            ("0.3,nan", "shading.chiang.pheomelanin"),
        ] {
            let e = opts(&["--model", "chiang", "--melanin", value])
                .scene()
                .unwrap_err();
            let m = e.to_string();
            assert!(matches!(&e, CliError::Usage(_)), "{value}: {m}");
            assert!(
                m.starts_with("--melanin = ")
                    && m.contains(key)
                    && (m.contains("[0, 50]") || m.contains("finite")),
                "{value}: {m}"
            );
            assert_eq!(e.exit_code(), 2, "{value}");
        }
        // A bad pheomelanin of the model stays the model's when --melanin sets only the
        // eumelanin (a scene file's is refused as the file loads, naming the file).
        let mut model = ShadingModel::Chiang(pelage::scene::ChiangParams {
            pheomelanin: Some(-1.0),
            ..Default::default()
        });
        let melanin = opts(&["--melanin", "0.3"]);
        let e = melanin.apply_chiang_options(&mut model).unwrap_err();
        let e = melanin.blame(e);
        assert!(
            matches!(&e, CliError::Render(pelage::Error::Param(p)) if p.name == "shading.chiang.pheomelanin"),
            "{e}"
        );
        let e = opts(&["--melanin", "0.3,-1"]).blame(CliError::Render(pelage::Error::Param(
            ParamError::new("shading.chiang.pheomelanin", -1.0, "must be in [0, 50]"),
        )));
        assert!(e.to_string().starts_with("--melanin = -1.0"), "{e}");
    }

    #[test]
    fn every_key_of_the_option_table_is_set_by_its_option() {
        let given = opts(&["--strands", "5", "--shadow-res", "64", "--melanin", "1,1"]);
        let none = opts(&[]);
        for (option, key) in OPTION_KEYS {
            assert!(given.sets(option, key), "{option} {key}");
            assert_eq!(
                none.sets(option, key),
                *option == "--size",
                "{option} {key}"
            );
        }
    }

    /// The command line accepts exactly the tables' names and aliases (the names scene
    /// files write), and each parses to its row's method.
    #[test]
    fn the_options_accept_the_method_tables() {
        use clap::CommandFactory;
        #[derive(clap::Parser)]
        struct Cli {
            #[command(flatten)]
            opts: SceneOpts,
        }
        fn check<T: Named>(cmd: &clap::Command, option: &str) {
            let arg = cmd
                .get_arguments()
                .find(|a| a.get_long() == Some(option))
                .expect(option);
            let values = arg.get_possible_values();
            assert_eq!(values.len(), T::NAMES.len(), "--{option}");
            for (value, row) in values.iter().zip(T::NAMES) {
                assert_eq!(value.get_name(), row.name, "--{option}");
                let aliases: Vec<&str> = value.get_name_and_aliases().skip(1).collect();
                assert_eq!(aliases, row.aliases, "--{option} {}", row.name);
            }
        }
        let cmd = Cli::command();
        check::<Transparency>(&cmd, "oit");
        check::<ShadowParams>(&cmd, "shadow");
        check::<ShadingModel>(&cmd, "model");
        let parse = |args: &[&str]| {
            <Cli as clap::Parser>::try_parse_from(std::iter::once("x").chain(args.iter().copied()))
                .map(|cli| cli.opts)
        };
        for (row, m) in ShadowParams::NAMES.iter().enumerate() {
            for name in std::iter::once(m.name).chain(m.aliases.iter().copied()) {
                let opts = parse(&["--shadow", name]).expect(name);
                assert_eq!(opts.shadow.map(|s| s.row()), Some(row), "{name}");
            }
        }
        assert!(parse(&["--oit", "k-buffer"]).is_err());
    }
}
