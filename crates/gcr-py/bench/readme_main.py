"""The README's Python block as a script (the files go to the current directory)."""

import gcr

scene = gcr.Scene.load("cornell-box")
solution = gcr.solve(scene)  # the program's defaults: quality="good", seed=1
metrics = solution.write(image="cornell.png", mesh="cornell.glb", metrics="cornell.json")
