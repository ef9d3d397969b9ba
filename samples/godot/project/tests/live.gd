extends "res://tests/checks.gd"
# HandsimWorld's live path: create(sides) + step(dt, frames), fed with the recorded session's frames through
# recorded_frame() (Godot's float32 Vector3 and Quat, as a live tracker would give them). The hand must grasp the lid
# once and open it to its 90-degree limit, as in the replay; the hash is printed but not compared (float32 inputs
# are not the recording's doubles, so it need not be the same). Then bad frames: each must fail naming the argument and leave the world unchanged.
# Run by run_godot.sh: godot3-server --path <project> --script res://tests/live.gd. Prints "live: N passed, M failed".


func expect_error(sim, result, prefix, what):
	expect(result == false, what + ": returned " + str(result))
	expect(sim.last_error().begins_with(prefix), what + ": message '" + sim.last_error() + "' should start with '"
		+ prefix + "'")


func with_entry(frame, key, index, value):
	var copy = frame.duplicate(true)
	var array = copy[key]
	array[index] = value
	copy[key] = array
	return copy


func _init():
	var replay = HandsimWorld.new()
	expect(replay.open(ProjectSettings.globalize_path("res://session.hsframes")), "open: " + replay.last_error())
	var live = HandsimWorld.new()
	expect(live.create(PoolIntArray([1])), "create([right]): " + live.last_error())
	var grasps = 0
	var lid_max = 0.0
	for i in range(replay.step_count()):
		if not live.step(1.0 / 60.0, [replay.recorded_frame(i, 0)]):
			expect(false, "step %d: %s" % [i, live.last_error()])
			break
		for event in live.events():
			if event["type"] == "grasp_begin":
				grasps += 1
		lid_max = max(lid_max, live.lid_angle())
	expect(grasps == 1, "one grasp of the lid, got %d" % grasps)
	expect(rad2deg(lid_max) > 89.9, "the lid opened to its limit, got %.3f deg" % rad2deg(lid_max))
	print("live: grasp_begin %d lid_max_deg %.3f state_hash %s" % [grasps, rad2deg(lid_max), live.state_hash()])

	# Bad frames leave the world as it was.
	var frame = replay.recorded_frame(0, 0)
	var before = live.state_hash()
	var short = frame.duplicate(true)
	var positions = short["positions"]
	positions.resize(25)
	short["positions"] = positions
	expect_error(live, live.step(1.0 / 60.0, [frame, frame]), "step: frames: 2 frames for 1 hand", "two frames")
	expect_error(live, live.step(1.0 / 60.0, [short]), "step: frames[0].positions: must hold 26", "25 positions")
	expect_error(live, live.step(1.0 / 60.0, [with_entry(frame, "rotations", 3, Vector3())]),
		"step: frames[0].rotations[3]: must be a Quat", "a Vector3 as a rotation")
	var no_rotations = frame.duplicate(true)
	no_rotations.erase("rotations")
	expect_error(live, live.step(1.0 / 60.0, [no_rotations]), "step: frames[0].rotations: must be an Array",
		"no rotations")
	expect_error(live, live.step(1.0 / 60.0, [with_entry(frame, "positions", 0, Vector3(NAN, 0, 0))]), "step: ",
		"a NaN palm position")
	expect(live.last_error().find("position") >= 0, "the NaN names the position: " + live.last_error())
	expect_error(live, live.step(1.0 / 60.0, [with_entry(frame, "rotations", 1, Quat(0, 0, 0, 2))]), "step: ",
		"a rotation of length 2")
	expect_error(live, live.step(0.0, [frame]), "step: ", "dt 0")
	expect(live.last_error().find("dt") >= 0, "dt 0 names dt: " + live.last_error())
	expect_error(live, live.step("x", [frame]), "step: takes (dt", "dt as a String")
	expect_error(live, live.step(1.0 / 60.0, [42]), "step: frames[0]: must be a Dictionary", "a frame as an int")
	expect_error(live, live.step_next(), "step_next: no session", "step_next on a live world")
	expect_error(live, live.create(PoolIntArray([1, 2])), "create: sides[1]: must be 0 (left) or 1 (right)",
		"a side of 2")
	expect(live.state_hash() == before, "bad frames changed the world")
	expect(live.step(1.0 / 60.0, [null]), "a null frame is an untracked hand: " + live.last_error())
	expect(live.step(1.0 / 60.0, []), "no frames: every hand untracked: " + live.last_error())
	print("live: %d passed, %d failed" % [passed, failed])
	OS.exit_code = 0 if failed == 0 else 1
	quit()
