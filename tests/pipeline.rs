//! End to end: `streakfit run pipelines/test.toml` (two tiny synthetic folders → extract → fit →
//! report), the stage cache, malformed pipelines (exit code 2 naming the key), and the report
//! opened in headless Chromium with every image loaded.
//!
//! Run with `cargo test --release --test pipeline`. Chromium is looked for as `$CHROMIUM`,
//! `chromium`, `chromium-browser`, `google-chrome`; the browser check fails when none is found
//! (CI installs Debian's `chromium`).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const EXE: &str = env!("CARGO_BIN_EXE_streakfit");

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A fresh scratch folder with a copy of `pipelines/test.toml` (runs write relative to it).
fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("streakfit-pipeline-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("pipelines")).unwrap();
    std::fs::copy(
        repo().join("pipelines/test.toml"),
        dir.join("pipelines/test.toml"),
    )
    .unwrap();
    dir
}

fn run(dir: &Path, args: &[&str]) -> Output {
    Command::new(EXE)
        .args(args)
        .current_dir(dir)
        // The materials presets of this checkout, whatever the working directory.
        .env(
            "STREAKFIT_MATERIALS",
            repo().join("datasets/materials.toml"),
        )
        .output()
        .expect("streakfit runs")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// `src="..."` values of every `<img>` in an HTML page.
fn img_sources(html: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = html;
    while let Some(i) = rest.find("<img ") {
        rest = &rest[i + 5..];
        let end = rest.find('>').unwrap();
        let tag = &rest[..end];
        let s = tag.find("src=\"").expect("img has src") + 5;
        let e = tag[s..].find('"').unwrap();
        out.push(tag[s..s + e].to_string());
    }
    out
}

fn chromium() -> Option<String> {
    let mut candidates: Vec<String> = Vec::new();
    if let Ok(c) = std::env::var("CHROMIUM") {
        candidates.push(c);
    }
    candidates.extend(["chromium", "chromium-browser", "google-chrome"].map(String::from));
    candidates.into_iter().find(|c| {
        Command::new(c)
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success())
    })
}

#[test]
fn tiny_pipeline_runs_end_to_end_caches_and_renders_in_chromium() {
    let dir = scratch("e2e");
    let out = run(&dir, &["run", "pipelines/test.toml"]);
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert_eq!(
        out.status.code(),
        Some(0),
        "stdout:\n{stdout}\nstderr:\n{stderr}"
    );

    // Every stage ran once, in order, and the summary names them.
    for stage in [
        "synth steel",
        "synth rubber",
        "extract steel",
        "extract rubber",
        "fit",
        "report",
    ] {
        assert!(
            stdout.contains(&format!("{stage:<26} ran")),
            "{stage} missing:\n{stdout}"
        );
    }
    assert!(stdout.contains("images: 12 ("), "{stdout}");
    assert!(
        stdout.contains("report: reports/test/index.html"),
        "{stdout}"
    );

    // Stage outputs where the module doc says, each with its stamp.
    let work = dir.join("work/test");
    for sub in [
        "synth/steel",
        "synth/rubber",
        "extract/steel",
        "extract/rubber",
        "fit",
    ] {
        assert!(
            work.join(sub).join(".streakfit-stage.json").exists(),
            "{sub}"
        );
    }
    let shots = std::fs::read_dir(work.join("synth/steel"))
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .unwrap()
                .file_name()
                .to_string_lossy()
                .starts_with("shot_")
        })
        .count();
    assert_eq!(shots, 6);
    assert!(work.join("extract/steel/angles.parquet").exists());

    // The steel fit recovers Table 1's restitution from six clean shots (round trip).
    let fit: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(work.join("fit/fit.json")).unwrap()).unwrap();
    let steel = fit["fits"]
        .as_array()
        .unwrap()
        .iter()
        .find(|f| f["material"] == "steel")
        .expect("a steel fit");
    let e = steel["e"].as_f64().expect("e identified");
    assert!((e - 0.92).abs() < 0.05, "steel e = {e}");

    // The report: HTML, Markdown, each figure as PNG + SVG, every <img> a file that decodes.
    let report = dir.join("reports/test");
    let html = std::fs::read_to_string(report.join("index.html")).unwrap();
    let md = std::fs::read_to_string(report.join("report.md")).unwrap();
    assert!(html.contains("Coefficients against the paper's Table 1"));
    assert!(
        md.contains("| steel bearings |") && md.contains("| rubber balls |"),
        "{md}"
    );
    assert!(
        !html.contains("http://") && !html.contains("https://"),
        "report must not fetch"
    );
    for name in [
        "fig05_regime_map",
        "fig14_paths_billiard",
        "fig15_paths_rubber",
        "steel_fig09_tan",
        "steel_fig10_deflection",
        "steel_fig11_delta2_regimes",
        "steel_fig12_delta2_jump",
        "steel_residuals",
        "steel_regime_map",
        "steel_paths_psi45",
        "rubber_fig12_delta2_jump",
    ] {
        assert!(
            report.join(format!("figures/{name}.svg")).exists(),
            "{name}.svg"
        );
        assert!(
            html.contains(&format!("figures/{name}.png")),
            "{name} not in the page"
        );
    }
    let sources = img_sources(&html);
    assert!(sources.len() >= 17 + 2, "{} images", sources.len());
    assert!(
        sources.iter().any(|s| s.starts_with("overlays/steel/")),
        "no overlay gallery"
    );
    for s in &sources {
        let img = image::open(report.join(s)).unwrap_or_else(|e| panic!("{s}: {e}"));
        assert!(img.width() > 100 && img.height() > 100, "{s}");
    }

    // A second run is all cache hits; a changed fit setting reruns fit and report only.
    let out2 = run(&dir, &["run", "pipelines/test.toml"]);
    let stdout2 = text(&out2.stdout);
    assert_eq!(out2.status.code(), Some(0), "{}", text(&out2.stderr));
    assert_eq!(stdout2.matches(" cached ").count(), 6, "{stdout2}");
    let p = dir.join("pipelines/test.toml");
    let changed = std::fs::read_to_string(&p)
        .unwrap()
        .replace("bootstrap = 0", "bootstrap = 2");
    std::fs::write(&p, changed).unwrap();
    let out3 = run(&dir, &["run", "pipelines/test.toml"]);
    let stdout3 = text(&out3.stdout);
    assert_eq!(out3.status.code(), Some(0), "{}", text(&out3.stderr));
    assert!(
        stdout3.contains(&format!("{:<26} cached", "extract steel")),
        "{stdout3}"
    );
    assert!(stdout3.contains(&format!("{:<26} ran", "fit")), "{stdout3}");
    assert!(
        stdout3.contains(&format!("{:<26} ran", "report")),
        "{stdout3}"
    );

    // `streakfit report` makes the same kind of report from the stage files by hand.
    let manual = run(
        &dir,
        &[
            "report",
            "work/test/extract/steel/angles.parquet",
            "work/test/extract/rubber/angles.parquet",
            "--fit",
            "work/test/fit/fit.json",
            "--overlays",
            "work/test/extract/steel/overlays",
            "--overlays",
            "work/test/extract/rubber/overlays",
            "--out",
            "manual",
        ],
    );
    assert_eq!(manual.status.code(), Some(0), "{}", text(&manual.stderr));
    let manual_html = std::fs::read_to_string(dir.join("manual/index.html")).unwrap();
    assert!(manual_html.contains("figures/steel_fig12_delta2_jump.png"));
    assert!(manual_html.contains("overlays/steel-angles/"));
    assert!(manual_html.contains("overlays/rubber-angles/"));
    let bad = run(
        &dir,
        &[
            "report",
            "work/test/extract/steel/angles.parquet",
            "--overlays",
            "a",
            "--overlays",
            "b",
            "--out",
            "m",
        ],
    );
    assert_eq!(bad.status.code(), Some(2));
    assert!(text(&bad.stderr).contains("--overlays"));

    // Headless Chromium: the page renders and every image has loaded (naturalWidth > 0).
    // A copy of the page with a small check script sits beside it, so relative links resolve.
    let browser = chromium().expect(
        "headless Chromium is needed for this test (apt-get install chromium, or set $CHROMIUM)",
    );
    let probe = report.join("probe.html");
    let script = "<script>window.addEventListener('load',()=>{const imgs=[...document.images];\
        const bad=imgs.filter(i=>!(i.complete&&i.naturalWidth>0)).map(i=>i.getAttribute('src'));\
        const d=document.createElement('pre');d.id='probe';\
        d.textContent='IMAGES '+imgs.length+' BROKEN '+bad.length+' ['+bad.join(',')+']';\
        document.body.appendChild(d);});</script>";
    std::fs::write(&probe, html.replace("</body>", &format!("{script}</body>"))).unwrap();
    let dom = Command::new(&browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--allow-file-access-from-files",
            "--virtual-time-budget=10000",
            "--dump-dom",
        ])
        .arg(format!("file://{}", probe.display()))
        .output()
        .expect("chromium runs");
    let dom_text = text(&dom.stdout);
    let line = dom_text
        .lines()
        .find(|l| l.contains("id=\"probe\">IMAGES "))
        .unwrap_or_else(|| panic!("no probe result; stderr:\n{}", text(&dom.stderr)));
    assert!(
        line.contains(&format!("IMAGES {} BROKEN 0 ", sources.len())),
        "{line}"
    );
    // And a screenshot of the top of the page is not blank.
    let shot = report.join("probe.png");
    let status = Command::new(&browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--window-size=1200,1600",
        ])
        .arg(format!("--screenshot={}", shot.display()))
        .arg(format!("file://{}", report.join("index.html").display()))
        .output()
        .expect("chromium runs");
    assert!(shot.exists(), "no screenshot: {}", text(&status.stderr));
    let png = image::open(&shot).unwrap().to_rgb8();
    let dark = png
        .pixels()
        .filter(|p| p.0.iter().all(|&c| c < 100))
        .count();
    assert!(dark > 2000, "screenshot looks blank ({dark} dark pixels)");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn malformed_pipelines_exit_2_naming_the_key() {
    let dir = scratch("bad");
    let base = std::fs::read_to_string(dir.join("pipelines/test.toml")).unwrap();
    let cases = [
        (
            base.replace("shots = 6", "shots = \"six\""),
            "folders[0].synth.shots",
        ),
        (
            base.replace("material = \"steel\"", "material = \"glass\""),
            "folders[0].synth.material",
        ),
        (
            base.replace("[report]", "[report]\ncolour = \"red\""),
            "report.colour",
        ),
        (
            base.replace("regime = \"auto\"", "regime = \"sideways\""),
            "fit.regime",
        ),
        (base.replace("name = \"test\"", "name = 7"), "'name'"),
    ];
    for (i, (content, key)) in cases.iter().enumerate() {
        let p = dir.join(format!("pipelines/bad{i}.toml"));
        std::fs::write(&p, content).unwrap();
        let out = run(&dir, &["run", &format!("pipelines/bad{i}.toml")]);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "case {i}: {err}");
        assert!(err.contains(key), "case {i}: expected '{key}' in: {err}");
        assert!(
            !dir.join("work").exists(),
            "case {i}: a malformed pipeline must not run stages"
        );
    }
    let out = run(&dir, &["run", "pipelines/missing.toml"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("missing.toml"));
    let _ = std::fs::remove_dir_all(&dir);
}
