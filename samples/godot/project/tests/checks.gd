extends SceneTree
# What the Godot test scripts share: a pass/fail count and expect(). Each test extends this script and prints
# "<name>: N passed, M failed" at its end.

const HandsimWorld = preload("res://addons/handsim/handsim_world.gdns")

var passed = 0
var failed = 0


func expect(condition, what):
	if condition:
		passed += 1
	else:
		failed += 1
		printerr("FAIL: ", what)
