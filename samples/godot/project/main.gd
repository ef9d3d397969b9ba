extends Spatial
# Replays a recorded handsim session (a frame stream, session.hsframes) in the jewelry-box scene: one recorded
# frame per physics tick, the box's bodies and the skinned hand mesh drawn from handsim's state.
#
# The recorded dt is used, not the engine's delta: the recorded state hashes are reached only with the same
# inputs. A live tracker would pass delta instead.
#
# Command-line options (after `--`): --session=PATH (default res://session.hsframes), --no-normals (skip the
# per-frame normals), --quit-at-end (always on under the headless server), --screenshot=PATH (with a renderer:
# saves the last frame as a PNG, then quits). On quitting it prints one line,
#   handsim_godot steps N state_hash 0x... first_mismatch M grasp_begin G lid_max_deg A hand_vertices V surfaces S
# and exits 1 when the session could not be opened or a step's hash differs from the recorded one.

const HandsimWorld = preload("res://addons/handsim/handsim_world.gdns")

var sim
var hands = []        # MeshInstance per hand, an ArrayMesh rebuilt every tick
var indices = []      # PoolIntArray per hand (Godot's winding), fetched once: the topology never changes
var bodies = {}       # name -> MeshInstance (a box of the body's half extents)
var with_normals = true
var quit_at_end = false
var grasp_begins = 0
var lid_max = 0.0
var vertex_count = 0
var screenshot = ""


func _ready():
	var path = ProjectSettings.globalize_path("res://session.hsframes")
	quit_at_end = OS.get_name() == "Server"
	for arg in OS.get_cmdline_args():
		if arg.begins_with("--session="):
			path = arg.substr(len("--session="), len(arg))
		elif arg == "--no-normals":
			with_normals = false
		elif arg == "--quit-at-end":
			quit_at_end = true
		elif arg.begins_with("--screenshot="):
			screenshot = arg.substr(len("--screenshot="), len(arg))
	sim = HandsimWorld.new()
	if sim == null:
		printerr("handsim_godot: the HandsimWorld class did not load (see the GDNative errors above)")
		_quit(1)
		return
	if not sim.open(path):
		printerr("handsim_godot: ", sim.last_error())
		_quit(1)
		return
	for h in range(sim.hand_count()):
		var mesh_instance = MeshInstance.new()
		mesh_instance.mesh = ArrayMesh.new()
		add_child(mesh_instance)
		hands.append(mesh_instance)
		indices.append(sim.hand_indices(h))
	var state = sim.bodies()
	for name in state.keys():
		var box = CubeMesh.new()
		box.size = state[name]["half_extents"] * 2.0
		var mesh_instance = MeshInstance.new()
		mesh_instance.mesh = box
		add_child(mesh_instance)
		bodies[name] = mesh_instance
	_place_bodies(state)
	var camera = Camera.new()
	var target = state["base"]["transform"].origin  # the box stands on a table: look at it from the front right
	camera.look_at_from_position(target + Vector3(0.25, 0.22, 0.38), target + Vector3(0.0, 0.05, 0.0), Vector3.UP)
	add_child(camera)
	var light = DirectionalLight.new()
	light.rotation_degrees = Vector3(-50.0, 30.0, 0.0)
	add_child(light)


func _physics_process(_delta):
	if sim == null or sim.step_index() >= sim.step_count():
		return
	if not sim.step_next():
		printerr("handsim_godot: ", sim.last_error())
		_quit(1)
		return
	for event in sim.events():
		if event["type"] == "grasp_begin":
			grasp_begins += 1
	lid_max = max(lid_max, sim.lid_angle())
	_place_bodies(sim.bodies())
	for h in range(hands.size()):
		_draw_hand(h)
	if sim.step_index() == sim.step_count():
		_finish()


func _place_bodies(state):
	for name in state.keys():
		bodies[name].transform = state[name]["transform"]


func _draw_hand(h):
	var arrays = []
	arrays.resize(Mesh.ARRAY_MAX)
	arrays[Mesh.ARRAY_VERTEX] = sim.hand_vertices(h)
	if with_normals:
		arrays[Mesh.ARRAY_NORMAL] = sim.hand_normals(h)
	arrays[Mesh.ARRAY_INDEX] = indices[h]
	vertex_count = arrays[Mesh.ARRAY_VERTEX].size()
	var mesh = hands[h].mesh
	if mesh.get_surface_count() > 0:
		mesh.surface_remove(0)
	mesh.add_surface_from_arrays(Mesh.PRIMITIVE_TRIANGLES, arrays)


func _finish():
	var surfaces = 0
	for hand in hands:
		surfaces += hand.mesh.get_surface_count()
	print("handsim_godot steps %d state_hash %s first_mismatch %d grasp_begin %d lid_max_deg %.3f hand_vertices %d surfaces %d"
		% [sim.step_index(), sim.state_hash(), sim.first_mismatch(), grasp_begins, rad2deg(lid_max), vertex_count,
		   surfaces])
	if screenshot != "":
		yield(VisualServer, "frame_post_draw")  # the last step drawn
		var image = get_viewport().get_texture().get_data()
		image.flip_y()  # the viewport texture is stored bottom-up
		image.save_png(screenshot)
		quit_at_end = true
	if quit_at_end:
		_quit(0 if sim.first_mismatch() < 0 else 1)


func _quit(code):
	sim = null  # _physics_process stops here: quit() takes effect at the end of the frame
	OS.exit_code = code
	get_tree().quit()
