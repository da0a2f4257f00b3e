//! `explobot`: the twin's command-line tool.

fn main() {
    eprintln!("explobot: the scenario runner is not built yet (issue 4)");
    std::process::exit(2);
}
