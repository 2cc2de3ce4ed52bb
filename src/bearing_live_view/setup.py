from setuptools import setup

PACKAGE = "bearing_live_view"

setup(
    name=PACKAGE,
    version="0.1.0",
    packages=[PACKAGE],
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + PACKAGE]),
        ("share/" + PACKAGE, ["package.xml"]),
    ],
    install_requires=["setuptools"],
    zip_safe=False,
    maintainer="bearing-monitor maintainers",
    maintainer_email="maintainers@bearing-monitor.invalid",
    description="The live view: the running graph served to Foxglove over its WebSocket protocol.",
    license="Apache-2.0",
    entry_points={
        "console_scripts": [
            "live_view = bearing_live_view.executables:live_view",
        ],
    },
)
