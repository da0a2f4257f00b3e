//! Diagnostic: prints, at every change of Cute's idea of the robot's cell, where the robot
//! really is (offset from that cell's centre and heading error).
use twin::runner::Lockstep;
use twin::setup::RunSetup;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args().nth(1);
    let loaded = match &path {
        Some(p) => RunSetup::load(std::path::Path::new(p))?,
        None => RunSetup::builtin_default()?,
    };
    let mut run = Lockstep::new(loaded, None)?;
    let mut last = None;
    let mut collisions = 0;
    while run.step() {
        let (x, y, h) = run.cute().robot();
        let c = run.body().world().collisions();
        if last != Some((x, y, h)) || c != collisions {
            let p = run.body().pose();
            let (cx, cy) = run.frame().cell_center(x as usize, y as usize);
            let want = h.world_angle().to_degrees();
            let mut err = p.theta.to_degrees() - want;
            while err > 180.0 {
                err -= 360.0;
            }
            while err < -180.0 {
                err += 360.0;
            }
            println!(
                "t={:7.2} cute=({x},{y},{h:?}) dx={:+.3} dy={:+.3} dtheta={:+.1} coll={c} status={:?}",
                run.now().as_secs_f64(),
                p.x - cx,
                p.y - cy,
                err,
                run.cute().status()
            );
            last = Some((x, y, h));
            collisions = c;
        }
    }
    Ok(())
}
