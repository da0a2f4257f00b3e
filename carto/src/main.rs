//! `carto`: the robot controller binary.

fn main() {
    eprintln!("carto: not built yet (issue 5)");
    std::process::exit(2);
}
