use super::*;
use crate::session::Waiting;
use robot_model::grid::Move;

#[test]
fn layout_fits_map_inside_region_below_toolbar() {
    let view = CuteView { region: Rect::new(0.5, 0.0, 1.0, 1.0), inset_bottom: 30.0 };
    let window = Vec2::new(1280.0, 720.0);
    let l = MapLayout::compute(window, &view, 8, 10);
    let r = l.map_rect();
    assert!(r.min.x >= 640.0 + MAP_PADDING - 0.5, "{r:?}");
    assert!(r.max.x <= 1280.0 - MAP_PADDING + 0.5, "{r:?}");
    assert!(r.min.y >= TOOLBAR_HEIGHT + MAP_PADDING - 0.5, "{r:?}");
    assert!(r.max.y <= 720.0 - 30.0 - MAP_PADDING + 0.5, "{r:?}");
    assert_eq!(l.cell, l.cell.floor());
    // Width-limited: 10 columns over 620 px.
    assert_eq!(l.cell, 62.0);
}

#[test]
fn cell_at_inverts_cell_rect_and_rejects_outside() {
    let l = MapLayout::compute(Vec2::new(800.0, 600.0), &CuteView::default(), 20, 20);
    for (row, col) in [(0, 0), (19, 19), (7, 13)] {
        let r = l.cell_rect(row, col);
        assert_eq!(l.cell_at(r.center()), Some((row as u8, col as u8)));
        assert_eq!(l.cell_at(r.min + Vec2::splat(0.01)), Some((row as u8, col as u8)));
    }
    let m = l.map_rect();
    assert_eq!(l.cell_at(m.min - Vec2::splat(1.0)), None);
    assert_eq!(l.cell_at(m.max + Vec2::splat(1.0)), None);
    assert_eq!(l.cell_at(Vec2::new(m.max.x + 0.5, m.center().y)), None);
}

/// A blocked move is drawn on the side the two cells share, whichever order they are given in.
#[test]
fn shared_side_is_the_edge_between_two_neighbours() {
    let l = MapLayout::compute(Vec2::new(800.0, 600.0), &CuteView::default(), 5, 5);
    let (a, right, below) = (l.cell_rect(2, 2), l.cell_rect(2, 3), l.cell_rect(3, 2));
    let side = l.shared_side((2, 2), (2, 3)).unwrap();
    assert_eq!(side, (Vec2::new(a.max.x, a.min.y), a.max));
    assert_eq!((side.0.x, side.1.x), (right.min.x, right.min.x), "the left side of the right cell");
    assert_eq!(l.shared_side((2, 3), (2, 2)), Some(side));
    let side = l.shared_side((3, 2), (2, 2)).unwrap();
    assert_eq!(side, (Vec2::new(a.min.x, a.max.y), a.max));
    assert_eq!(side.0.y, below.min.y);
    assert_eq!(l.shared_side((2, 2), (3, 3)), None);
    assert_eq!(l.shared_side((2, 2), (2, 4)), None);
}

#[test]
fn tiny_windows_still_give_positive_cells() {
    let l = MapLayout::compute(Vec2::new(50.0, 40.0), &CuteView::default(), 256, 256);
    assert!(l.cell > 0.0);
    assert!(l.map_rect().width() > 0.0);
}

#[test]
fn logical_to_world_puts_origin_at_window_centre() {
    let win = Vec2::new(1280.0, 720.0);
    assert_eq!(logical_to_world(win, Vec2::new(640.0, 360.0)), Vec2::ZERO);
    assert_eq!(logical_to_world(win, Vec2::new(0.0, 0.0)), Vec2::new(-640.0, 360.0));
    assert_eq!(logical_to_world(win, Vec2::new(1280.0, 720.0)), Vec2::new(640.0, -360.0));
}

#[test]
fn colours_follow_the_original_cute() {
    let lum = |v| {
        let [r, g, b] = cell_rgb(v);
        u32::from(r) + u32::from(g) + u32::from(b)
    };
    assert!(lum(CellValue::Obstacle) < 100);
    assert!(lum(CellValue::Free) > 450);
    assert!(lum(CellValue::Unknown) > lum(CellValue::Free));
    let [r, g, b] = cell_rgb(CellValue::Robot);
    assert!(b > r && b > g);
    let [r, g, b] = cell_rgb(CellValue::Waypoint);
    assert!(r > 200 && g < 100 && b < 100);
    let [r, g, _] = cell_rgb(CellValue::Destination);
    assert!(r > 200 && g > 100);
    // Every value is distinguishable.
    let all = [0u8, 1, 2, 3, 4, 5].map(|v| CellValue::from_u8(v).map(cell_rgb));
    for i in 0..all.len() {
        for j in i + 1..all.len() {
            assert_ne!(all[i], all[j]);
        }
    }
}

#[test]
fn popups_for_no_path_connection_lost_and_obstacle() {
    assert_eq!(popup_for(&CuteEvent::NoPath { x: 1, y: 2 }).map(|p| p.title), Some("No path".into()));
    assert_eq!(popup_for(&CuteEvent::ConnectionLost).map(|p| p.title), Some("Connection lost".into()));
    let p = popup_for(&CuteEvent::ObstacleMet { x: 3, y: 4 }).unwrap();
    assert!(p.text.contains("(3, 4)"));
    assert!(popup_for(&CuteEvent::MoveTimeout { waiting_for: Waiting::MoveDone }).is_some());
    assert!(popup_for(&CuteEvent::MoveRejected { command: Move::Forward }).is_some());
    assert!(popup_for(&CuteEvent::Connected).is_none());
    assert!(popup_for(&CuteEvent::Reached { x: 0, y: 0 }).is_none());
    assert!(popup_for(&CuteEvent::ProtocolError { message: "x".into(), fatal: false }).is_none());
}

#[test]
fn ui_state_deduplicates_waiting_popups_and_bounds_the_log() {
    let mut s = CuteUiState::default();
    s.record(&CuteEvent::ConnectionLost);
    s.record(&CuteEvent::ConnectionLost);
    assert_eq!(s.popups.len(), 1);
    for i in 0..20 {
        s.record(&CuteEvent::Reached { x: i, y: 0 });
    }
    assert_eq!(s.log.len(), LOG_LINES);
    assert_eq!(s.log.back().map(String::as_str), Some("reached (19, 0)"));
}

/// A session whose map is known free except an obstacle at (1, 1), connected and ready.
fn ready_session() -> Cute {
    use protocol::link::{GuiMessage, MsgOrder};
    let mut cute = Cute::new(crate::session::CuteConfig { rows: 3, cols: 4, ..Default::default() }).unwrap();
    cute.on_connected(robot_model::time::Instant::ZERO);
    let mut bytes = GuiMessage::RobotPositionReceived.to_bytes(MsgOrder::BigEndian);
    // Unsolicited positions and obstacles are mirrored on the map.
    for (x, y) in [(0, 1), (0, 2), (0, 3), (1, 3), (2, 3), (2, 2), (2, 1), (2, 0), (1, 0), (0, 0)] {
        bytes.extend(GuiMessage::SetRobotPosition { x, y }.to_bytes(MsgOrder::BigEndian));
    }
    bytes.extend(GuiMessage::SetObstaclePosition { x: 1, y: 1 }.to_bytes(MsgOrder::BigEndian));
    cute.on_bytes(robot_model::time::Instant::from_millis(1), &bytes);
    cute.take_outgoing();
    cute.take_events();
    assert!(cute.is_ready());
    cute
}

/// Runs `click_to_go` once with a left click at the centre of `cell` in a 400 x 300 window.
fn click(cute: Cute, cell: (usize, usize)) -> (Cute, CuteUiState) {
    let mut app = App::new();
    let mut window = Window { resolution: WindowResolution::new(400, 300), ..Window::default() };
    let layout = MapLayout::compute(Vec2::new(400.0, 300.0), &CuteView::default(), 3, 4);
    window.set_cursor_position(Some(layout.cell_rect(cell.0, cell.1).center()));
    app.world_mut().spawn((window, PrimaryWindow));
    let mut buttons = ButtonInput::<MouseButton>::default();
    buttons.press(MouseButton::Left);
    app.insert_resource(buttons)
        .insert_resource(CuteView::default())
        .insert_resource(CuteSession(cute))
        .init_resource::<CuteUiState>()
        .add_systems(Update, click_to_go::<CuteSession>);
    app.update();
    let ui = app.world().resource::<CuteUiState>().clone();
    let cute = app.world_mut().remove_resource::<CuteSession>().unwrap().0;
    (cute, ui)
}

#[test]
fn click_on_a_free_cell_sends_the_robot_there() {
    let (mut cute, ui) = click(ready_session(), (2, 3));
    assert_eq!(cute.status(), Status::Moving);
    assert_eq!(cute.map().destination(), Some((2, 3)));
    assert_eq!(ui.notice.as_deref(), Some("going to (2, 3)"));
    // Only SEND_MOVES_TRAJECTORY frames went out.
    let frames = protocol::link::Decoder::default().feed(&cute.take_outgoing());
    assert!(!frames.is_empty());
    for f in frames {
        assert!(matches!(f, Ok(protocol::link::GuiMessage::SendMovesTrajectory { .. })), "{f:?}");
    }
}

#[test]
fn click_on_an_obstacle_explains_and_does_not_move() {
    let (mut cute, ui) = click(ready_session(), (1, 1));
    assert_eq!(cute.status(), Status::Idle);
    assert!(cute.take_outgoing().is_empty());
    let notice = ui.notice.unwrap_or_default();
    assert!(notice.starts_with("cannot go to (1, 1)"), "{notice}");
}

#[test]
fn status_text_names_link_mission_and_counts() {
    let cute = Cute::new(crate::session::CuteConfig { rows: 3, cols: 4, ..Default::default() }).unwrap();
    let t = status_text(&cute);
    assert!(t.starts_with("disconnected | idle | robot (0, 0) facing"), "{t}");
    assert!(t.ends_with("free 1 obstacles 0 unknown 11"), "{t}");
    let config = crate::session::CuteConfig { compat: Compat::Explobot2024, ..Default::default() };
    let mut cute = Cute::new(config).unwrap();
    assert!(status_text(&cute).starts_with("compat 2024, unknown cells planned as free | "));
    cute.on_connected(robot_model::time::Instant::ZERO);
    cute.stop();
    assert!(status_text(&cute).starts_with("compat 2024, next batch dropped | "));
}
