//! Times a scenario run with the bare lockstep loop (no Bevy), for comparison with `explobot run`.
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args().nth(1).ok_or("usage: plainloop SCENARIO")?;
    let loaded = twin::setup::RunSetup::load(std::path::Path::new(&path))?;
    let mut run = twin::runner::Lockstep::new(loaded, None)?;
    let t = std::time::Instant::now();
    run.run_to_end(|_| {});
    let wall = t.elapsed().as_secs_f64();
    let r = run.report(wall);
    println!("{}: {:.1} s sim in {:.3} s wall = {:.0}x", r.scenario, r.sim_time_s, wall, r.real_time_factor);
    Ok(())
}
