"""The studio's layout and diagrams in the browser (issue 29 items 3 and 4): an icon of its own
for every component type, and a page that fits at the window sizes people use.

Everything here is read from the rendered page (element rectangles, SVG attributes), with
real mouse events where the user would act."""

from tests.studio.helpers import K, open_studio, tid


def schema_types(page):
    """The component types /api/schema lists, as the page's own request gets them."""
    return page.evaluate("""async () => {
        const token = new URLSearchParams(location.search).get("token");
        const s = await (await fetch("/api/schema", {headers: {"X-Kinetwork-Token": token}})).json();
        // the library's types (the last choice is a subsystem's, any definition name)
        return s.properties.components.items.oneOf.map(o => o.properties.type.const).filter(Boolean);
    }""")


def test_every_type_of_the_schema_has_an_icon_of_its_own(page, studio):
    """Each type /api/schema names is in the palette with a drawn icon, never the "?"
    fallback; two libraries' grounds differ, and a block on the diagram shows its type's."""
    open_studio(page, studio)
    types = schema_types(page)
    assert len(types) > 100
    icons = page.evaluate("""(types) => Object.fromEntries(types.map(t => {
        const item = document.querySelector(`[data-testid="palette-${t}"]`);
        const svg = item && item.querySelector("svg[data-icon]");
        return [t, svg ? [svg.dataset.icon, svg.querySelectorAll("path, circle, rect, ellipse, text").length] : null];
    }))""", types)
    missing = [t for t, icon in icons.items() if icon is None]
    assert not missing, f"not in the palette: {missing}"
    fallback = sorted(t for t, (key, _) in icons.items() if key == "Unknown")
    assert not fallback, f"types drawn with the '?' fallback: {fallback}"
    empty = sorted(t for t, (_, shapes) in icons.items() if shapes == 0)
    assert not empty, f"icons that draw nothing: {empty}"
    assert icons["electrical.Ground"][0] != icons["multibody.Ground"][0]

    page.fill(tid("palette-search"), "PointMass")
    page.wait_for_selector(tid("palette-multibody.PointMass"))
    page.dblclick(tid("palette-multibody.PointMass"))
    page.wait_for_function("() => window.__kinetwork.doc.components.length === 1")
    name = K(page, "K.doc.components[0].name")
    assert page.get_attribute(f'{tid(f"node-{name}")} svg[data-icon]', "data-icon") == "PointMass"
    assert not page.errors, page.errors
