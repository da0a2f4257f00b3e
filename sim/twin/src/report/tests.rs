use super::*;

fn report(unphysical: Unphysical) -> Report {
    Report {
        scenario: "t".into(),
        seed: 1,
        known_room: false,
        known_echoes: false,
        sim_time_s: 10.0,
        wall_time_s: 0.01,
        real_time_factor: 1000.0,
        steps: 2000,
        mission_complete: true,
        mission_time_s: Some(9.0),
        mission_errors: Vec::new(),
        grid: (2, 2),
        map: MapScore::default(),
        coverage: 1.0,
        map_accuracy: 1.0,
        moves: 3,
        collisions: 0,
        touches: TouchReport::default(),
        belief: BeliefReport::default(),
        first_contact: None,
        unphysical,
        final_pose: (0.0, 0.0, 0.0),
        final_cell: Some((0, 0)),
        cute_cell: (0, 0),
        localisation: Localisation::default(),
        links: Vec::new(),
        faults_injected: 0,
        reconnects: 0,
        link_log_sha256: String::new(),
        checks: Vec::new(),
        passed: false,
    }
}

#[test]
fn a_run_that_left_physics_cannot_pass() {
    let expect = Expectations { collisions_max: Some(0), ..Expectations::default() };
    let mut sound = report(Unphysical { fastest_m_s: 0.3, fastest_rad_s: 2.0, ..Unphysical::default() });
    sound.check(&expect);
    assert!(sound.passed);
    assert_eq!(sound.checks.len(), 1, "a sound run gets no `physical` check: {:?}", sound.checks);
    let thrown = Unphysical { steps: 3, first_at_s: Some(25.6), fastest_m_s: 14.0, fastest_rad_s: 157.0 };
    let mut thrown = report(thrown);
    thrown.check(&expect);
    assert!(!thrown.passed);
    let physical = thrown.checks.iter().find(|c| c.name == "physical").expect("a physical check");
    assert!(!physical.pass && physical.actual.contains("25.600 s"), "{physical:?}");
    assert!(thrown.to_text().contains("physics         NOT PHYSICAL from 25.600 s"), "{}", thrown.to_text());
    assert!(thrown.summary_text().contains("physics NOT PHYSICAL from 25.600 s"));
    assert!(!sound.summary_text().contains("physics"));
}
