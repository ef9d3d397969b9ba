// Stand-ins for the UnityEngine names samples/unity/HandsimHands.cs uses, written from Unity's public scripting
// reference: same namespaces, type kinds, member names and signatures; bodies do nothing useful. They exist so that
// ctest unity_sample_compiles can compile the sample without Unity and catch name clashes and API misuse. Unity's
// own Pose, Event and EventType are declared too, because they collide with handsim's and the sample must qualify
// them. Not a Unity emulation: nothing here is run.
using System;
using System.Collections.Generic;

namespace UnityEngine
{
    public class Object { }
    public class Component : Object
    {
        public GameObject gameObject { get { return null; } }
        public Transform transform { get { return null; } }
        public bool TryGetComponent<T>(out T component) { component = default(T); return false; }
    }
    public class Behaviour : Component { public bool enabled { get; set; } }
    public class MonoBehaviour : Behaviour { }
    public sealed class GameObject : Object { public bool activeInHierarchy { get { return false; } } }
    public class Transform : Component
    {
        public Vector3 position { get; set; }
        public Quaternion rotation { get; set; }
        public Vector3 lossyScale { get { return Vector3.one; } }
        public void SetPositionAndRotation(Vector3 position, Quaternion rotation) { }
    }
    public class Collider : Component { }
    public class BoxCollider : Collider { public Vector3 size { get; set; } }
    public sealed class MeshFilter : Component { public Mesh mesh { get; set; } }
    public sealed class Mesh : Object
    {
        public Rendering.IndexFormat indexFormat { get; set; }
        public Vector3[] vertices { get; set; }
        public int[] triangles { get; set; }
        public void RecalculateNormals() { }
        public void RecalculateBounds() { }
    }
    public struct Vector3
    {
        public float x, y, z;
        public Vector3(float x, float y, float z) { this.x = x; this.y = y; this.z = z; }
        public static Vector3 zero { get { return new Vector3(0, 0, 0); } }
        public static Vector3 one { get { return new Vector3(1, 1, 1); } }
        public static Vector3 Scale(Vector3 a, Vector3 b) { return new Vector3(a.x * b.x, a.y * b.y, a.z * b.z); }
        public static Vector3 operator *(float d, Vector3 a) { return new Vector3(d * a.x, d * a.y, d * a.z); }
        public static Vector3 operator *(Vector3 a, float d) { return d * a; }
    }
    public struct Quaternion
    {
        public float x, y, z, w;
        public Quaternion(float x, float y, float z, float w) { this.x = x; this.y = y; this.z = z; this.w = w; }
        public static Quaternion identity { get { return new Quaternion(0, 0, 0, 1); } }
    }
    public struct Pose
    {
        public Vector3 position;
        public Quaternion rotation;
        public Pose(Vector3 position, Quaternion rotation) { this.position = position; this.rotation = rotation; }
        public static Pose identity { get { return new Pose(Vector3.zero, Quaternion.identity); } }
    }
    public sealed class Event { }
    public enum EventType { MouseDown = 0 }
    public static class Time { public static float deltaTime { get { return 0; } } }
    public static class Debug { public static void Log(object message) { } }
    [AttributeUsage(AttributeTargets.Field)]
    public class TooltipAttribute : Attribute { public TooltipAttribute(string tooltip) { } }
    public interface ISubsystem { bool running { get; } }
    public static class SubsystemManager
    {
        public static void GetSubsystems<T>(List<T> subsystems) where T : ISubsystem { subsystems.Clear(); }
    }
}

namespace UnityEngine.Rendering
{
    public enum IndexFormat { UInt16 = 0, UInt32 = 1 }
}
