import bpy

settings = bpy.context.scene.hc_smooth

settings.method = "HC"
settings.keep_sharp_edges = False
settings.sharpness_angle = 0.5235987901687622
settings.auto_amount = False
settings.keep_in_place = True
settings.alpha = 0.01
settings.beta = 0.6
settings.iterations = 100
settings.mode = "SIMULTANEOUS"
settings.tolerance = 0.0
settings.max_deviation = 0.0
