//! Shared by the CLI's integration tests: a temporary workspace with manifests, and the
//! `aabench` binary run in it as a real process.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output};
use std::sync::Mutex;
use std::sync::mpsc::Receiver;
use std::time::Duration;

use serde_json::{Value, json};

/// lavapipe uses every core: one aabench process at a time keeps the tests' timings sane.
pub static SERIAL: Mutex<()> = Mutex::new(());

pub struct Workspace {
    pub dir: PathBuf,
}

impl Workspace {
    pub fn new(name: &str) -> Workspace {
        let dir = std::env::temp_dir().join(format!("aabench-cli-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("scenes")).unwrap();
        Workspace { dir }
    }

    /// Writes scenes/<name>.json for a generated scene at 64×48, with `edit` applied.
    pub fn manifest(&self, name: &str, generator: &str, edit: impl Fn(&mut Value)) -> PathBuf {
        let mut manifest = json!({
            "schema_version": 1,
            "name": name,
            "gltf": format!("cache/{generator}.glb"),
            "generate": { "generator": generator, "seed": 1 },
            "resolution": { "quick": [64, 48], "nightly": [128, 96] },
            "lights": [{ "position": [0.5, 0.5, 2.0], "intensity": 4.0, "range": 20.0 }],
            "ambient": [0.05, 0.05, 0.05],
            "stall_iterations": 16,
            // Fixed, as the suite's scenes have it: the tests' thresholds assume this light
            // level (a manifest without it is metered: own_scene.rs).
            "tonemap": { "exposure": 1.0 }
        });
        edit(&mut manifest);
        let path = self.dir.join("scenes").join(format!("{name}.json"));
        std::fs::write(&path, serde_json::to_string_pretty(&manifest).unwrap()).unwrap();
        path
    }

    pub fn command(&self, args: &[&str]) -> Command {
        let mut command = Command::new(env!("CARGO_BIN_EXE_aabench"));
        command.args(args).current_dir(&self.dir).env("CI", "1");
        command
    }

    pub fn run(&self, args: &[&str]) -> Output {
        self.command(args).output().expect("aabench runs")
    }

    /// The run.json of the only run under reports/.
    pub fn record(&self) -> Value {
        let runs: Vec<PathBuf> =
            std::fs::read_dir(self.dir.join("reports")).unwrap().map(|e| e.unwrap().path()).collect();
        assert_eq!(runs.len(), 1, "{runs:?}");
        serde_json::from_slice(&std::fs::read(runs[0].join("run.json")).unwrap()).expect("run.json is JSON")
    }

    pub fn run_dir(&self) -> PathBuf {
        std::fs::read_dir(self.dir.join("reports")).unwrap().next().unwrap().unwrap().path()
    }

    /// The display image of a mode record of the only run.
    pub fn display(&self, mode: &Value) -> image::DynamicImage {
        let file = self.run_dir().join(mode["images"]["display"].as_str().expect("a display image"));
        image::open(&file).unwrap_or_else(|e| panic!("{}: {e}", file.display()))
    }
}

impl Drop for Workspace {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

pub fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// The scene of a run record by its name.
pub fn scene<'a>(record: &'a Value, name: &str) -> &'a Value {
    record["scenes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["name"] == name)
        .unwrap_or_else(|| panic!("no {name}"))
}

pub fn mode<'a>(scene: &'a Value, id: &str) -> &'a Value {
    scene["modes"].as_array().unwrap().iter().find(|m| m["mode"] == id).unwrap_or_else(|| panic!("no {id}"))
}

/// Copies the folder `from` to `to`, recursively.
pub fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let path = entry.unwrap().path();
        let target = to.join(path.file_name().unwrap());
        if path.is_dir() {
            copy_dir(&path, &target)
        } else {
            std::fs::copy(&path, &target).map(drop).unwrap()
        }
    }
}

/// Reads a JSON file.
pub fn read_json(path: &Path) -> Value {
    serde_json::from_slice(&std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())))
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Writes a JSON file.
pub fn write_json(path: &Path, value: &Value) {
    std::fs::write(path, serde_json::to_vec_pretty(value).unwrap()).unwrap();
}

/// The lines a child writes to its piped stderr, as they come (read on a thread: an unread
/// pipe would fill and block the child).
pub fn stderr_lines(child: &mut Child) -> Receiver<String> {
    let stderr = child.stderr.take().expect("stderr piped");
    let (send, lines) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        use std::io::BufRead;
        for line in std::io::BufReader::new(stderr).lines().map_while(Result::ok) {
            let _ = send.send(line);
        }
    });
    lines
}

/// Reads lines until one contains `text`; panics if the child goes quiet for two minutes.
pub fn wait_for_line(lines: &Receiver<String>, text: &str) {
    loop {
        let line =
            lines.recv_timeout(Duration::from_secs(120)).unwrap_or_else(|_| panic!("no line with `{text}`"));
        if line.contains(text) {
            return;
        }
    }
}

/// Whether a test's precondition holds (root, Chromium). A test that needs one is `#[ignore]`d
/// with its reason, so that a plain `cargo test` lists it as not run; run anyway (`--ignored`,
/// as `.ci/run` does), it fails where `CI` is set, and elsewhere says that it skipped.
pub fn precondition(holds: bool, what: &str) -> bool {
    if holds {
        return true;
    }
    assert!(std::env::var_os("CI").is_none(), "{what}, and CI is set: this test must run here");
    eprintln!("skipped: {what}");
    false
}

/// A generated scene (seed 1), written to a temporary folder, imported through glTF and the
/// folder removed.
pub fn generated_scene(
    generator: aabench_renderer::scene::generate::Generator,
) -> aabench_renderer::scene::Scene {
    let dir = std::env::temp_dir().join(format!("aabench-{generator}-test-{}", std::process::id()));
    let path = dir.join(format!("{generator}.glb"));
    generator.write(1, &path).expect("write the scene");
    let scene = aabench_renderer::scene::load_gltf(&path).expect("import the scene");
    let _ = std::fs::remove_dir_all(&dir);
    scene
}

/// `scene` on a renderer (and device) of its own at `width` × `height`: the rig a scene without
/// lights of its own gets (`scenes.rs`) over `ambient`, plain colour, no stall.
pub fn plain_renderer(
    scene: &aabench_renderer::scene::Scene,
    camera: &aabench_renderer::scene::Camera,
    [width, height]: [u32; 2],
    ambient: f32,
) -> aabench_renderer::SceneRenderer {
    let gpu = std::sync::Arc::new(aabench_renderer::Gpu::new().expect("a Vulkan adapter (lavapipe)"));
    let lighting = aabench_renderer::scene::Lighting {
        lights: aabench::run::scenes::default_rig(),
        ambient: glam::Vec3::splat(ambient),
        background: glam::Vec3::new(0.2, 0.3, 0.5),
        exposure: 1.0,
    };
    let settings = aabench_renderer::RenderSettings {
        width,
        height,
        stall_iterations: 0,
        adaptive: Default::default(),
        color: aabench_renderer::ColorSettings::plain(),
    };
    aabench_renderer::SceneRenderer::new(gpu, scene, camera, &lighting, settings).expect("scene upload")
}
