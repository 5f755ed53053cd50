//! Shell conventions: completion scripts for bash, zsh and fish and the man pages, made from
//! the command-line definition itself.

use std::process::Command;

fn asperity(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(args)
        .output()
        .expect("asperity runs");
    assert!(out.status.success(), "{args:?}: {out:?}");
    String::from_utf8(out.stdout).expect("UTF-8")
}

/// Each script completes the subcommands and their options, in its shell's own syntax.
#[test]
fn completion_scripts_name_every_subcommand() {
    for (shell, marker) in [
        ("bash", "complete -F _asperity"),
        ("zsh", "#compdef asperity"),
        ("fish", "complete -c asperity"),
    ] {
        let script = asperity(&["completions", shell]);
        assert!(script.contains(marker), "{shell}: {marker} missing");
        for word in ["run", "converge", "sweep", "mesh-info", "resume", "threads"] {
            assert!(script.contains(word), "{shell}: {word} missing");
        }
    }
}

/// bash reads the script without a syntax error and then completes `asperity ru` to `run`.
#[test]
fn the_bash_script_completes_a_subcommand() {
    let script = asperity(&["completions", "bash"]);
    let test = format!(
        "{script}\nCOMP_WORDS=(asperity ru); COMP_CWORD=1; COMP_LINE='asperity ru'; \
         COMP_POINT=11; _asperity asperity ru asperity; printf '%s\\n' \"${{COMPREPLY[@]}}\""
    );
    let out = Command::new("bash").args(["-c", &test]).output().unwrap();
    assert!(out.status.success(), "{out:?}");
    let words = String::from_utf8(out.stdout).unwrap();
    assert_eq!(words.lines().collect::<Vec<_>>(), ["run"], "{words}");
}

#[test]
fn the_man_page_is_roff_with_every_subcommand() {
    let page = asperity(&["man"]);
    assert!(page.contains(".TH asperity 1"), "{page}");
    for word in ["run", "converge", "sweep", "schema", "completions"] {
        assert!(page.contains(word), "{word} missing");
    }
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("man1");
    asperity(&["man", "--out", out.to_str().unwrap()]);
    for page in ["asperity.1", "asperity-run.1", "asperity-sweep-run.1"] {
        let text = std::fs::read_to_string(out.join(page)).unwrap();
        assert!(text.starts_with(".ie") || text.contains(".TH"), "{page}");
    }
    // Written again over the earlier pages; a page of another origin, or a link in a page's
    // place, is refused (exit code 2) and left as it was.
    asperity(&["man", "--out", out.to_str().unwrap()]);
    std::fs::write(out.join("asperity-run.1"), "my notes").unwrap();
    let refused = || {
        Command::new(env!("CARGO_BIN_EXE_asperity"))
            .args(["man", "--out", out.to_str().unwrap()])
            .output()
            .unwrap()
    };
    assert_eq!(refused().status.code(), Some(2));
    assert_eq!(read(&out.join("asperity-run.1")), "my notes");
    #[cfg(unix)]
    {
        let outside = dir.path().join("outside.txt");
        std::fs::write(&outside, "keep").unwrap();
        std::fs::remove_file(out.join("asperity-run.1")).unwrap();
        std::os::unix::fs::symlink(&outside, out.join("asperity-run.1")).unwrap();
        assert_eq!(refused().status.code(), Some(2));
        assert_eq!(read(&outside), "keep");
    }
}

fn read(path: &std::path::Path) -> String {
    std::fs::read_to_string(path).unwrap()
}

/// The exit status paragraph of `--help` and the man page names every code of the guide's
/// table (docs/guide/troubleshooting.md), and no other.
#[test]
fn the_help_names_the_exit_codes_of_the_guide() {
    let page = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/docs/guide/troubleshooting.md"
    ))
    .unwrap();
    let table: Vec<String> = page[page.find("**Exit codes**").unwrap()..]
        .lines()
        .skip_while(|l| !l.starts_with('|'))
        .take_while(|l| l.starts_with('|'))
        .filter_map(|l| l.split('|').nth(1).map(str::trim))
        .filter(|c| c.parse::<u8>().is_ok())
        .map(str::to_string)
        .collect();
    let help = asperity(&["--help"]);
    let status = &help[help
        .rfind("Exit status:")
        .expect("an exit status paragraph")..];
    let named: Vec<String> = status
        .split(';')
        .filter_map(|part| part.split_whitespace().find(|w| w.parse::<u8>().is_ok()))
        .map(str::to_string)
        .collect();
    assert_eq!(named, table, "{status}");
}
