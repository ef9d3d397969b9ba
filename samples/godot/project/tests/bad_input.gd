extends "res://tests/checks.gd"
# Bad input to HandsimWorld: every call must fail with a message naming the argument, never crash, and leave an
# open session as it was. Run by run_godot.sh: godot3-server --path <project> --script res://tests/bad_input.gd
# Prints "bad_input: N passed, M failed" and exits 1 on any failure.


func expect_error(sim, result, bad_result, prefix, what):
	expect(typeof(result) == typeof(bad_result) and result == bad_result, what + ": returned " + str(result))
	expect(sim.last_error().begins_with(prefix), what + ": message '" + sim.last_error() + "' should start with '"
		+ prefix + "'")


func _init():
	var session = ProjectSettings.globalize_path("res://session.hsframes")
	var work = OS.get_user_data_dir()
	var sim = HandsimWorld.new()
	expect_error(sim, sim.open(42), false, "open: path: must be a String", "open(42)")
	expect_error(sim, sim.open(), false, "open: takes 1 argument", "open()")
	expect_error(sim, sim.open(work + "/missing.hsframes"), false, "open: path: cannot open", "a missing file")
	expect_error(sim, sim.step_next(), false, "step_next: no session is open", "step_next before open")
	expect_error(sim, sim.hand_vertices(0), null, "hand_vertices: hand: must be 0..", "hand_vertices before open")

	# Truncated and foreign files.
	var source = File.new()
	source.open(session, File.READ)
	var bytes = source.get_buffer(source.get_len())
	source.close()
	var cut = File.new()
	cut.open(work + "/cut.hsframes", File.WRITE)
	cut.store_buffer(bytes.subarray(0, bytes.size() - 2))
	cut.close()
	expect_error(sim, sim.open(work + "/cut.hsframes"), false, "open: path:", "a truncated stream")
	expect(sim.last_error().find("expected") >= 0, "a truncated stream names the expected size")
	var other = File.new()
	other.open(work + "/other.hsframes", File.WRITE)
	other.store_string("not a frame stream at all, just text")
	other.close()
	expect_error(sim, sim.open(work + "/other.hsframes"), false, "open: path:", "a foreign file")
	# A header that claims 10 million steps in a small file: refused before anything is allocated.
	var huge = bytes.subarray(0, 27)
	huge[16] = 0x80
	huge[17] = 0x96
	huge[18] = 0x98
	huge[19] = 0x00
	var big = File.new()
	big.open(work + "/huge.hsframes", File.WRITE)
	big.store_buffer(huge)
	big.close()
	expect_error(sim, sim.open(work + "/huge.hsframes"), false, "open: path:", "a header claiming 10^7 steps")
	expect(sim.last_error().find("expected") >= 0, "the claimed size is named: " + sim.last_error())
	var head = File.new()
	head.open(work + "/head.hsframes", File.WRITE)
	head.store_buffer(bytes.subarray(0, 12))
	head.close()
	expect_error(sim, sim.open(work + "/head.hsframes"), false, "open: path:", "a file cut inside its header")

	# An open session is left as it was by bad calls.
	expect(sim.open(session), "the real session opens: " + sim.last_error())
	for _i in range(20):
		sim.step_next()
	var before = sim.state_hash()
	expect_error(sim, sim.hand_vertices(1), null, "hand_vertices: hand: must be 0..0", "hand 1 of 1")
	expect_error(sim, sim.hand_normals(-1), null, "hand_normals: hand: must be 0..0", "hand -1")
	expect_error(sim, sim.hand_indices("0"), null, "hand_indices: hand: must be an int", "hand as a String")
	expect_error(sim, sim.step_next(1), false, "step_next: takes 0 argument", "step_next(1)")
	expect(sim.state_hash() == before and sim.step_index() == 20, "bad calls changed the session")
	expect(sim.hand_vertices(0).size() == sim.hand_normals(0).size(), "vertices and normals of one size")
	expect(sim.hand_indices(0).size() % 3 == 0, "whole triangles")
	# A failed open closes the old session cleanly (no dangling world).
	expect(not sim.open(work + "/missing.hsframes") and sim.step_count() == 0 and sim.state_hash() == "",
		"a failed open leaves no session")
	print("bad_input: %d passed, %d failed" % [passed, failed])
	OS.exit_code = 0 if failed == 0 else 1
	quit()
