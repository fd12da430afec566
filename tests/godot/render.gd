# Renders the sphere grid of tests/godot/test_godot.c in Godot 3 (GLES3), lit only by the
# panoramas that `ibl bake --target godot` wrote, and saves one PNG per view. Run headless:
#   xvfb-run -a godot3 --audio-driver Dummy --path PROJECT -s render.gd
# PROJECT holds project.godot and views.cfg, one section per view:
#   [NAME] panorama="/abs/engine_environment.exr" output="/abs/NAME.png"
#          exposure=1.0 background_energy=1.0 ambient_energy=1.0
# The scene (kept equal to test_godot.c's constants): a 256x256 view, a Camera at (0, 0, 8)
# looking down -Z with a vertical field of view of 35 degrees, four spheres of radius 0.9 at
# (-1, 1, 0) metal roughness 0 (a mirror), (1, 1, 0) metal 0.5, (-1, -1, 0) metal 1 and
# (1, -1, 0) white diffuse (metallic 0, specular 0, roughness 1).
extends SceneTree

const VIEW_SIZE = 256
const FRAMES_BEFORE_CAPTURE = 3

var views = []
var frames = 0


func sphere(position, metallic, roughness, specular):
	var material = SpatialMaterial.new()
	material.albedo_color = Color(1, 1, 1)
	material.metallic = metallic
	material.roughness = roughness
	material.metallic_specular = specular
	var mesh = SphereMesh.new()
	mesh.radius = 0.9
	mesh.height = 1.8
	mesh.radial_segments = 256
	mesh.rings = 128
	var instance = MeshInstance.new()
	instance.mesh = mesh
	instance.material_override = material
	instance.translation = position
	return instance


# The bake's panorama as Godot's sky: the ambient light and the reflections both come from it.
func environment_from(sky, exposure, background_energy, ambient_energy):
	var environment = Environment.new()
	environment.background_mode = Environment.BG_SKY
	environment.background_sky = sky
	environment.background_energy = background_energy
	environment.ambient_light_sky_contribution = 1.0
	environment.ambient_light_energy = ambient_energy
	environment.tonemap_mode = Environment.TONE_MAPPER_LINEAR
	environment.tonemap_exposure = exposure
	return environment


func sky_from(path):
	var image = Image.new()
	if image.load(path) != OK:
		printerr("render.gd: cannot load ", path)
		return null
	var texture = ImageTexture.new()
	texture.create_from_image(image, Texture.FLAG_FILTER)
	var sky = PanoramaSky.new()
	sky.radiance_size = Sky.RADIANCE_SIZE_256
	sky.panorama = texture
	return sky


func _init():
	var config = ConfigFile.new()
	if config.load("res://views.cfg") != OK:
		printerr("render.gd: cannot read views.cfg")
		quit(1)
		return
	var skies = {}
	for name in config.get_sections():
		var path = config.get_value(name, "panorama")
		if not skies.has(path):
			skies[path] = sky_from(path)
		if skies[path] == null:
			quit(1)
			return
		var viewport = Viewport.new()
		viewport.size = Vector2(VIEW_SIZE, VIEW_SIZE)
		viewport.own_world = true
		viewport.render_target_update_mode = Viewport.UPDATE_ALWAYS
		viewport.render_target_v_flip = true
		var camera = Camera.new()
		camera.fov = 35
		camera.translation = Vector3(0, 0, 8)
		camera.environment = environment_from(skies[path], config.get_value(name, "exposure", 1.0),
				config.get_value(name, "background_energy", 1.0),
				config.get_value(name, "ambient_energy", 1.0))
		camera.current = true
		viewport.add_child(camera)
		viewport.add_child(sphere(Vector3(-1, 1, 0), 1.0, 0.0, 0.5))
		viewport.add_child(sphere(Vector3(1, 1, 0), 1.0, 0.5, 0.5))
		viewport.add_child(sphere(Vector3(-1, -1, 0), 1.0, 1.0, 0.5))
		viewport.add_child(sphere(Vector3(1, -1, 0), 0.0, 1.0, 0.0))
		root.add_child(viewport)
		views.append([viewport, config.get_value(name, "output")])


func _idle(_delta):
	frames += 1
	if frames < FRAMES_BEFORE_CAPTURE:
		return false
	for view in views:
		var shot = view[0].get_texture().get_data()
		if shot.save_png(view[1]) != OK:
			printerr("render.gd: cannot write ", view[1])
			quit(1)
			return false
	quit(0)
	return false
